//! Units that users write in files and flags.
//!
//! Inside the toolkit lengths are millimetres and angles radians; a file
//! always states its units explicitly (they are never guessed), and these
//! enums convert between the file's unit and the internal one.

use std::fmt;
use std::str::FromStr;

/// The unit of angles in a file or on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AngleUnit {
    /// Degrees (`deg`).
    Deg,
    /// Radians (`rad`), the internal unit.
    Rad,
}

/// The unit of lengths in a file or on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LengthUnit {
    /// Millimetres (`mm`), the internal unit.
    Mm,
    /// Metres (`m`).
    M,
}

/// A unit name that is not one of the accepted spellings.
///
/// ```
/// use aacmm_core::io::AngleUnit;
/// let e = "degrees".parse::<AngleUnit>().unwrap_err();
/// assert_eq!(e.to_string(), "unknown angle unit `degrees`; accepted: `deg`, `rad`");
/// ```
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown {quantity} unit {}; accepted: {}",
    crate::error::quoted(given),
    accepted_list(accepted)
)]
pub struct UnknownUnit {
    /// `"angle"` or `"length"`.
    pub(crate) quantity: &'static str,
    /// What was given.
    pub(crate) given: String,
    /// The accepted spellings.
    pub accepted: &'static [&'static str],
}

fn accepted_list(accepted: &[&str]) -> String {
    accepted
        .iter()
        .map(|a| format!("`{a}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl AngleUnit {
    /// The accepted spellings, in the order of [`AngleUnit::ALL`].
    pub(crate) const NAMES: &'static [&'static str] = &["deg", "rad"];
    /// All angle units.
    pub const ALL: [AngleUnit; 2] = [AngleUnit::Deg, AngleUnit::Rad];

    /// The unit's spelling in files and flags.
    ///
    /// ```
    /// assert_eq!(aacmm_core::io::AngleUnit::Deg.name(), "deg");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            AngleUnit::Deg => "deg",
            AngleUnit::Rad => "rad",
        }
    }

    /// Converts a value in this unit to radians.
    ///
    /// ```
    /// use aacmm_core::io::AngleUnit;
    /// assert_eq!(AngleUnit::Deg.to_internal(180.0), std::f64::consts::PI);
    /// assert_eq!(AngleUnit::Rad.to_internal(1.5), 1.5);
    /// ```
    pub fn to_internal(self, x: f64) -> f64 {
        match self {
            AngleUnit::Deg => x.to_radians(),
            AngleUnit::Rad => x,
        }
    }

    /// Converts a value in radians to this unit.
    ///
    /// ```
    /// use aacmm_core::io::AngleUnit;
    /// assert_eq!(AngleUnit::Deg.from_internal(std::f64::consts::PI), 180.0);
    /// ```
    pub fn from_internal(self, x: f64) -> f64 {
        match self {
            AngleUnit::Deg => x.to_degrees(),
            AngleUnit::Rad => x,
        }
    }

    /// The value to write to a file for the internal value `x`: among the
    /// values within a few ulps of [`from_internal`](Self::from_internal)`(x)`,
    /// the one with the shortest decimal form that converts back to exactly
    /// `x`; if none does (possible, as the conversion is not onto), plain
    /// `from_internal(x)`, which converts back to within 1 ulp.
    ///
    /// ```
    /// use aacmm_core::io::AngleUnit;
    /// let x = AngleUnit::Deg.to_internal(-90.0);
    /// assert_eq!(AngleUnit::Deg.from_internal_exact(x), -90.0);
    /// ```
    pub fn from_internal_exact(self, x: f64) -> f64 {
        match self {
            AngleUnit::Rad => x,
            AngleUnit::Deg => invert_exactly(x, x.to_degrees(), |v| self.to_internal(v)),
        }
    }
}

impl LengthUnit {
    /// The accepted spellings, in the order of [`LengthUnit::ALL`].
    pub(crate) const NAMES: &'static [&'static str] = &["mm", "m"];
    /// All length units.
    pub const ALL: [LengthUnit; 2] = [LengthUnit::Mm, LengthUnit::M];

    /// The unit's spelling in files and flags.
    ///
    /// ```
    /// assert_eq!(aacmm_core::io::LengthUnit::M.name(), "m");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::M => "m",
        }
    }

    /// Converts a value in this unit to millimetres.
    ///
    /// ```
    /// use aacmm_core::io::LengthUnit;
    /// assert_eq!(LengthUnit::M.to_internal(0.375), 375.0);
    /// assert_eq!(LengthUnit::Mm.to_internal(0.375), 0.375);
    /// ```
    pub fn to_internal(self, x: f64) -> f64 {
        match self {
            LengthUnit::Mm => x,
            LengthUnit::M => x * 1000.0,
        }
    }

    /// Converts a value in millimetres to this unit.
    ///
    /// ```
    /// use aacmm_core::io::LengthUnit;
    /// assert_eq!(LengthUnit::M.from_internal(375.0), 0.375);
    /// ```
    pub fn from_internal(self, x: f64) -> f64 {
        match self {
            LengthUnit::Mm => x,
            LengthUnit::M => x / 1000.0,
        }
    }

    /// The value to write to a file for the internal value `x`; see
    /// [`AngleUnit::from_internal_exact`].
    ///
    /// ```
    /// use aacmm_core::io::LengthUnit;
    /// assert_eq!(LengthUnit::M.from_internal_exact(375.0), 0.375);
    /// ```
    pub fn from_internal_exact(self, x: f64) -> f64 {
        match self {
            LengthUnit::Mm => x,
            LengthUnit::M => invert_exactly(x, x / 1000.0, |v| self.to_internal(v)),
        }
    }
}

/// Among `guess` and its neighbours up to 4 ulps away, the value `v` with
/// `to_internal(v) == x` whose shortest decimal form is shortest (ties: the
/// nearest to `guess`); `guess` if there is none.
fn invert_exactly(x: f64, guess: f64, to_internal: impl Fn(f64) -> f64) -> f64 {
    if !guess.is_finite() {
        return guess;
    }
    // Candidates in order of distance from `guess` (guess, one ulp up, one
    // down, two up, …), so keeping only a strictly shorter one breaks ties
    // by nearness. Lengths are counted, not allocated: a campaign of 10⁶
    // touches writes 6·10⁶ readings through here.
    let (mut up, mut down) = (guess, guess);
    let mut candidates = [guess; 9];
    for pair in candidates[1..].chunks_exact_mut(2) {
        up = up.next_up();
        down = down.next_down();
        pair[0] = up;
        pair[1] = down;
    }
    let mut found = [0.0; 9];
    let mut n = 0;
    for v in candidates {
        if to_internal(v).to_bits() == x.to_bits() {
            found[n] = v;
            n += 1;
        }
    }
    match n {
        0 => guess,
        // Mostly only one converts back: nothing to compare.
        1 => found[0],
        _ => {
            let mut best = (debug_len(found[0]), found[0]);
            for &v in &found[1..n] {
                let len = debug_len(v);
                if len < best.0 {
                    best = (len, v);
                }
            }
            best.1
        }
    }
}

/// The length of `format!("{v:?}")`, without the string.
fn debug_len(v: f64) -> usize {
    struct Count(usize);
    impl std::fmt::Write for Count {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0 += s.len();
            Ok(())
        }
    }
    let mut count = Count(0);
    // Writing to a counter cannot fail.
    let _ = std::fmt::Write::write_fmt(&mut count, format_args!("{v:?}"));
    count.0
}

impl FromStr for AngleUnit {
    type Err = UnknownUnit;

    /// Parses `deg` or `rad` (exactly; no other spellings).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "deg" => Ok(AngleUnit::Deg),
            "rad" => Ok(AngleUnit::Rad),
            _ => Err(UnknownUnit {
                quantity: "angle",
                given: s.to_string(),
                accepted: AngleUnit::NAMES,
            }),
        }
    }
}

impl FromStr for LengthUnit {
    type Err = UnknownUnit;

    /// Parses `mm` or `m` (exactly; no other spellings).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "mm" => Ok(LengthUnit::Mm),
            "m" => Ok(LengthUnit::M),
            _ => Err(UnknownUnit {
                quantity: "length",
                given: s.to_string(),
                accepted: LengthUnit::NAMES,
            }),
        }
    }
}

impl fmt::Display for AngleUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The inversion as it was first written (a vector of candidates, each
    /// formatted to a string): the counted one must choose the same value.
    fn invert_by_strings(x: f64, guess: f64, to_internal: impl Fn(f64) -> f64) -> f64 {
        if !guess.is_finite() {
            return guess;
        }
        let mut candidates = vec![guess];
        let (mut up, mut down) = (guess, guess);
        for _ in 0..4 {
            up = up.next_up();
            down = down.next_down();
            candidates.push(up);
            candidates.push(down);
        }
        (candidates.into_iter())
            .filter(|&v| to_internal(v).to_bits() == x.to_bits())
            .min_by_key(|v| format!("{v:?}").len())
            .unwrap_or(guess)
    }

    #[test]
    fn the_counted_inversion_chooses_what_the_strings_chose() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let deg = |v: f64| AngleUnit::Deg.to_internal(v);
        let m = |v: f64| LengthUnit::M.to_internal(v);
        let mut differ_from_guess = 0;
        for i in 0..200_000 {
            // Random readings, and readings written with few decimals
            // (where a neighbour of the guess is often shorter).
            let written = match i % 3 {
                0 => rng.random_range(-400.0..400.0),
                1 => (rng.random_range(-4_000_000..4_000_000) as f64) / 10_000.0,
                _ => (rng.random_range(-4000..4000) as f64) / 8.0,
            };
            let x = deg(written);
            let counted = invert_exactly(x, x.to_degrees(), deg);
            assert_eq!(
                counted.to_bits(),
                invert_by_strings(x, x.to_degrees(), deg).to_bits()
            );
            differ_from_guess += usize::from(counted != x.to_degrees());
            let x = m(written);
            let counted = invert_exactly(x, x / 1000.0, m);
            assert_eq!(
                counted.to_bits(),
                invert_by_strings(x, x / 1000.0, m).to_bits()
            );
        }
        for x in [f64::NAN, f64::INFINITY, 0.0, -0.0, f64::MIN_POSITIVE, 1e300] {
            let (a, b) = (
                invert_exactly(x, x.to_degrees(), deg),
                invert_by_strings(x, x.to_degrees(), deg),
            );
            assert_eq!(a.to_bits(), b.to_bits(), "{x}");
        }
        assert!(
            differ_from_guess > 1000,
            "the neighbours were chosen {differ_from_guess} times"
        );
    }

    #[test]
    fn parse_and_display() {
        for u in AngleUnit::ALL {
            assert_eq!(u.name().parse::<AngleUnit>(), Ok(u));
            assert_eq!(u.to_string(), u.name());
        }
        for u in LengthUnit::ALL {
            assert_eq!(u.name().parse::<LengthUnit>(), Ok(u));
            assert_eq!(u.to_string(), u.name());
        }
        let e = "MM".parse::<LengthUnit>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown length unit `MM`; accepted: `mm`, `m`"
        );
        assert!("".parse::<AngleUnit>().is_err());
        assert!("degree".parse::<AngleUnit>().is_err());
    }

    #[test]
    fn conversions() {
        assert_eq!(
            AngleUnit::Deg.to_internal(90.0),
            std::f64::consts::FRAC_PI_2
        );
        assert_eq!(AngleUnit::Rad.from_internal(0.25), 0.25);
        assert_eq!(LengthUnit::M.to_internal(1.5), 1500.0);
        assert_eq!(LengthUnit::Mm.from_internal(1.5), 1.5);
    }

    #[test]
    fn exact_inverse_of_user_values() {
        // Values a user writes come back unchanged.
        for d in [
            -180.0, -90.0, -45.0, 0.0, 0.1, 1.0, 12.345, 30.0, 90.0, 179.999,
        ] {
            let x = AngleUnit::Deg.to_internal(d);
            assert_eq!(AngleUnit::Deg.from_internal_exact(x), d, "{d}");
        }
        for m in [0.0, 0.001, 0.05, 0.375, 1.2345678, -0.035] {
            let x = LengthUnit::M.to_internal(m);
            assert_eq!(LengthUnit::M.from_internal_exact(x), m, "{m}");
        }
    }

    #[test]
    fn exact_inverse_of_arbitrary_values() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..10_000 {
            let x: f64 = rng.random_range(-7.0..7.0);
            let d = AngleUnit::Deg.from_internal_exact(x);
            let back = AngleUnit::Deg.to_internal(d);
            // Exact where possible, within 1 ulp always.
            assert!((back - x).abs() <= x.abs() * f64::EPSILON, "{x} {back}");
            let l: f64 = rng.random_range(-1000.0..1000.0);
            let m = LengthUnit::M.from_internal_exact(l);
            let back = LengthUnit::M.to_internal(m);
            assert!((back - l).abs() <= l.abs() * f64::EPSILON, "{l} {back}");
        }
    }

    #[test]
    fn non_finite_passes_through() {
        assert!(AngleUnit::Deg.from_internal_exact(f64::NAN).is_nan());
        assert_eq!(
            LengthUnit::M.from_internal_exact(f64::INFINITY),
            f64::INFINITY
        );
    }
}
