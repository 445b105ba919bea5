//! What a calibration's observations are called, in the summary and the
//! verdict alike.

use crate::calibrate::Calibration;

/// What the observations are: touches, reference positions, points on
/// spheres, or several of them.
pub(crate) fn noun(c: &Calibration) -> &'static str {
    let has = |term: &str| c.dof.rows_of(term) > 0;
    match (c.dof.touch_rows > 0, has("positions"), has("spheres")) {
        (false, true, false) => "position",
        (false, false, true) => "sphere point",
        (true, false, false) | (false, false, false) => "touch",
        _ => "observation",
    }
}

/// What the outliers `o` are: their one kind
/// ([`crate::calibrate::checks::Outlier::noun`], `noun` for touches and
/// positions), or `observation` when they are of several.
pub(crate) fn outliers_noun<'a>(
    o: &'a [crate::calibrate::checks::Outlier],
    noun: &'a str,
) -> &'a str {
    let first = o.first().map_or(noun, |x| x.noun(noun));
    if o.iter().all(|x| x.noun(noun) == first) {
        first
    } else {
        "observation"
    }
}
