//! Reference positions handed in as arrays
//! (`aacmm_calibrate_options_set_positions`): checked as the library's
//! reader checks a positions file, each refusal naming the array and its
//! index (0-based, as C indexes it).

use std::ffi::c_char;

use aacmm_core::domain::{DEFAULT_FRAME, Positions};
use aacmm_core::error::quoted;
use aacmm_core::params::{supported_joints_text, supports_joints};

use crate::error::{AacmmStatus, Error};
use crate::ptr;

/// The name arrays go by in reports (a row's "line" is its 1-based index).
pub(crate) const ARRAYS: &str = "<arrays>";

/// The lengths of the position arrays, as given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lengths {
    pub(crate) joints: usize,
    pub(crate) q: usize,
    pub(crate) xyz: usize,
    pub(crate) frames: usize,
    pub(crate) frame_names: usize,
    pub(crate) uncertainty: usize,
}

impl Lengths {
    /// Whether every array is empty: no positions.
    pub(crate) fn none(&self) -> bool {
        [
            self.q,
            self.xyz,
            self.frames,
            self.frame_names,
            self.uncertainty,
        ]
        .iter()
        .all(|&n| n == 0)
    }

    /// The number of rows the lengths agree on, checked: `joints` one the
    /// toolkit has a kernel for (`AACMM_STATUS_UNSUPPORTED`), every length
    /// what `q_len / joints` rows imply (`AACMM_STATUS_LENGTH`).
    pub(crate) fn rows(&self) -> Result<usize, Error> {
        let joints = self.joints;
        if !supports_joints(joints) {
            return Err(Error::new(
                AacmmStatus::Unsupported,
                format!(
                    "joints = {joints}: the toolkit computes {}",
                    supported_joints_text()
                ),
            ));
        }
        if !self.q.is_multiple_of(joints) || self.q == 0 {
            return Err(Error::length(format!(
                "q_len = {}: a positive multiple of joints = {joints} (one row of readings per \
                 position)",
                self.q
            )));
        }
        let n = self.q / joints;
        let expect = |name: &str, got: usize, allowed: &[usize], what: &str| {
            if allowed.contains(&got) {
                Ok(())
            } else {
                Err(Error::length(format!(
                    "{name} = {got}, expected {what} for the {n} rows of q"
                )))
            }
        };
        expect("xyz_len", self.xyz, &[3 * n], &format!("{}", 3 * n))?;
        expect("frames_len", self.frames, &[0, n], &format!("0 or {n}"))?;
        expect(
            "uncertainty_len",
            self.uncertainty,
            &[0, n],
            &format!("0 or {n}"),
        )?;
        if self.frames == 0 && self.frame_names > 1 {
            return Err(Error::length(format!(
                "frame_names_len = {}, expected 0 or 1 without frames (every row in one frame)",
                self.frame_names
            )));
        }
        if self.frames > 0 && self.frame_names == 0 {
            return Err(Error::length(
                "frame_names_len = 0: frames index into frame_names, which holds none",
            ));
        }
        Ok(n)
    }
}

/// The frame names: each UTF-8 text (`AACMM_STATUS_INVALID_ARGUMENT`
/// otherwise), not empty and named once (`AACMM_STATUS_INPUT`).
///
/// # Safety
///
/// Each pointer is `NULL` or points to a NUL-terminated string.
pub(crate) unsafe fn frame_names(names: &[*const c_char]) -> Result<Vec<String>, Error> {
    let empty = "empty frame name: name the station or placement";
    // SAFETY: by the contract.
    unsafe { distinct_names(names, ("frame_names", "frame"), empty) }
}

/// The names of `tool_names`: as [`frame_names`], each trimmed.
///
/// # Safety
///
/// Each pointer is `NULL` or a NUL-terminated string.
pub(crate) unsafe fn tool_names(names: &[*const c_char]) -> Result<Vec<String>, Error> {
    let empty = "empty tool name: name a [[tool]] of the arm file (index 0 is its [probe])";
    // SAFETY: by the contract.
    let names = unsafe { distinct_names(names, ("tool_names", "tool"), empty) }?;
    Ok(names.into_iter().map(|n| n.trim().to_string()).collect())
}

/// The names of the array `array` (`what` each names): UTF-8, none empty
/// (refused with `empty`), none given twice.
///
/// # Safety
///
/// Each pointer is `NULL` or points to a NUL-terminated string.
unsafe fn distinct_names(
    names: &[*const c_char],
    (array, what): (&str, &str),
    empty: &str,
) -> Result<Vec<String>, Error> {
    let mut out: Vec<String> = ptr::try_vec(&format!("{array}_len"), names.len())?;
    for (k, &p) in names.iter().enumerate() {
        let arg = format!("{array}[{k}]");
        // SAFETY: NULL or NUL-terminated, by the contract.
        let s = unsafe { ptr::c_str(p, &arg) }?;
        let s = s
            .to_str()
            .map_err(|_| Error::invalid(format!("{arg} is not valid UTF-8")))?;
        if s.trim().is_empty() {
            return Err(input(format!("{arg}: {empty}")));
        }
        if let Some(j) = out.iter().position(|n| n == s) {
            return Err(input(format!(
                "{arg}: {} is {array}[{j}] too: give each {what} once",
                quoted(s)
            )));
        }
        out.push(s.to_string());
    }
    Ok(out)
}

/// `rows` with row `i`'s tool `of[i]` (0 the arm's probe, `k` the tool
/// `names[k - 1]`), every name used; `of` empty: every row the probe.
pub(crate) fn with_tools(
    rows: Positions,
    of: &[u32],
    names: &[String],
) -> Result<Positions, Error> {
    let n = rows.len();
    if of.len() != n && !(of.is_empty() && names.is_empty()) {
        return Err(Error::length(format!(
            "tools_len = {}: 0 or the {n} rows of the positions",
            of.len()
        )));
    }
    let mut rows = rows.without_tools();
    let mut used = vec![false; names.len()];
    for (i, &k) in of.iter().enumerate() {
        let name = match k as usize {
            0 => "",
            k => {
                let Some(name) = names.get(k - 1) else {
                    return Err(input(format!(
                        "tools[{i}] = {k}: tool_names holds {} name(s) (0 is the arm's [probe], \
                         k is tool_names[k - 1])",
                        names.len()
                    )));
                };
                used[k - 1] = true;
                name
            }
        };
        rows.set_tool_of(i, name);
    }
    if let Some(k) = used.iter().position(|u| !u) {
        return Err(input(format!(
            "tool_names[{k}]: {} is no row's tool (tools[i] = {}): give the names the rows use",
            quoted(&names[k]),
            k + 1
        )));
    }
    Ok(rows)
}

/// Per row of `n`, its orientation from `q` (4 values a row, `w, x, y, z`;
/// empty: none at all): four `NAN` for none, else four finite numbers of
/// unit length within the reader's tolerance — each refusal naming the
/// index (`AACMM_STATUS_LENGTH` for a length other than 0 or `4 n`).
pub(crate) fn orientations(q: &[f64], n: usize) -> Result<Vec<Option<[f64; 4]>>, Error> {
    use aacmm_core::domain::UNIT_QUATERNION_TOLERANCE;
    if q.is_empty() {
        return Ok(vec![None; n]);
    }
    if q.len() != 4 * n {
        return Err(Error::length(format!(
            "quaternions_len = {}, expected 0 or {} (4 per row) for the {n} rows set",
            q.len(),
            4 * n
        )));
    }
    (q.chunks_exact(4).enumerate())
        .map(|(i, c)| {
            if c.iter().all(|v| v.is_nan()) {
                return Ok(None);
            }
            if let Some(k) = c.iter().position(|v| !v.is_finite()) {
                return Err(input(format!(
                    "quaternions[{}] = {}: a row gives four finite numbers or four NAN (row {i})",
                    4 * i + k,
                    c[k]
                )));
            }
            let norm = c.iter().map(|v| v * v).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
                return Err(input(format!(
                    "quaternions[{}..{}]: has length {norm}, not 1 (a unit quaternion w, x, y, \
                     z; row {i})",
                    4 * i,
                    4 * i + 4
                )));
            }
            Ok(Some([c[0], c[1], c[2], c[3]]))
        })
        .collect()
}

fn input(message: String) -> Error {
    Error::new(AacmmStatus::Input, message)
}

/// The rows of the arrays (lengths checked by [`Lengths::rows`]), checked
/// as a positions file's: finite readings and positions, uncertainties
/// positive or `NAN` (not stated), frame indices in range, every frame
/// name used, and every frame with at least 3 distinct positions not on
/// one line. Each row is its own point, labelled `P1`, `P2`, … in row
/// order, its "line" its 1-based index.
pub(crate) fn rows(
    joints: usize,
    q: &[f64],
    xyz: &[f64],
    frames: &[u32],
    names: &[String],
    uncertainty: &[f64],
) -> Result<Positions, Error> {
    let n = q.len() / joints;
    if let Some(k) = q.iter().position(|v| !v.is_finite()) {
        return Err(input(format!(
            "q[{k}] = {}: readings must be finite numbers (row {}, joint {})",
            q[k],
            k / joints,
            k % joints + 1
        )));
    }
    if let Some(k) = xyz.iter().position(|v| !v.is_finite()) {
        return Err(input(format!(
            "xyz[{k}] = {} ({} of row {}): positions must be finite numbers (mm)",
            xyz[k],
            ["x", "y", "z"][k % 3],
            k / 3
        )));
    }
    // NAN: not stated; otherwise a finite number > 0.
    let stated_wrong = |u: f64| !(u.is_nan() || (u.is_finite() && u > 0.0));
    if let Some((i, &u)) = (uncertainty.iter().enumerate()).find(|&(_, &u)| stated_wrong(u)) {
        return Err(input(format!(
            "uncertainty[{i}] = {}: a standard uncertainty per coordinate (mm) is a finite \
             number > 0; NAN: not stated",
            aacmm_core::error::short(u)
        )));
    }
    if let Some((i, f)) = frames
        .iter()
        .enumerate()
        .find(|&(_, &f)| f as usize >= names.len())
    {
        return Err(input(format!(
            "frames[{i}] = {f}: an index into frame_names, which holds {}",
            names.len()
        )));
    }
    if !frames.is_empty()
        && let Some(k) = (0..names.len()).find(|&k| !frames.contains(&(k as u32)))
    {
        return Err(input(format!(
            "frame_names[{k}] ({}): no row of frames names it",
            quoted(&names[k])
        )));
    }
    let one = names.first().map_or(DEFAULT_FRAME, String::as_str);
    let mut out = Positions::new(joints);
    for i in 0..n {
        let frame = frames.get(i).map_or(one, |&f| names[f as usize].as_str());
        let x = [xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]];
        let u = uncertainty.get(i).copied().filter(|u| !u.is_nan());
        let reading = &q[i * joints..(i + 1) * joints];
        (out.try_push(&format!("P{}", i + 1), frame, reading, x, u, i + 1))
            .map_err(|e| Error::out_of_memory(e.to_string()))?;
    }
    if let Some((row, why)) = out.unregistrable_frame() {
        let arg = if frames.is_empty() {
            "xyz".to_string()
        } else {
            format!("frames[{row}]")
        };
        return Err(input(format!("{arg}: {why}")));
    }
    Ok(out)
}
