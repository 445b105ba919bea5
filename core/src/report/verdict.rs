//! The report's first section: whether the calibration may be used, and
//! why not — the same verdict as the command line's exit code, the summary
//! and `calibration.json`'s `/verdict`, so that someone sent only the page
//! cannot mistake a refused calibration for a good one. With it, what the
//! verdict rests on: the χ² test (or the robust scale's), the outliers by
//! `file:line`, and the held-out figures (held-out data, cross-validation)
//! when they ran.

use super::html::escape;
use super::{CalibrationInput, ValidationRow};
use crate::calibrate::Calibration;
use crate::calibrate::checks::{CHI_SQUARE_ALPHA, CHI_SQUARE_REFUSE};
use crate::session::Spelling;

/// Outliers listed by `file:line` (the rest are counted).
const LISTED_OUTLIERS: usize = 20;

/// The verdict section.
pub(crate) fn section(input: &CalibrationInput) -> String {
    let cal = input.calibration;
    let mut s = String::from("<section id=\"verdict\">\n<h2>Verdict</h2>\n");
    s += &headline(input.verdict);
    s += "<ul>\n";
    s += &format!("<li>{}</li>\n", fit_quality(cal));
    s += &format!("<li>{}</li>\n", outliers(cal));
    for line in held_out(&input.validation, input) {
        s += &format!("<li>{line}</li>\n");
    }
    s += "</ul>\n</section>\n";
    s
}

/// Usable or NOT usable, with the reasons and the notes.
fn headline(verdict: Option<&crate::session::Verdict>) -> String {
    let Some(v) = verdict else {
        return "<p><span class=\"bad\">No verdict</span>: this report was drawn from a \
                calibration alone, outside a session; whether it may be used (solver, \
                geometry, χ² test, validation) was not decided here.</p>\n"
            .to_string();
    };
    let mut s = if v.usable {
        "<p data-json=\"/verdict/usable\" data-value=\"true\"><span class=\"good\">Verdict: \
         usable.</span> The solver reached a confirmed minimum, the calibrated arm is the \
         nominal arm's kind of geometry, and the checks below agree.</p>\n"
            .to_string()
    } else {
        let mut s = "<p data-json=\"/verdict/usable\" data-value=\"false\"><span class=\"bad\">\
                     Verdict: NOT usable.</span> Do not use this calibration (the command exited \
                     1, and calibrated.toml is marked so); why:</p>\n<ul>\n"
            .to_string();
        for r in &v.reasons {
            s += &format!(
                "<li class=\"bad\">{}</li>\n",
                escape(&r.describe(Spelling::Cli))
            );
        }
        s + "</ul>\n"
    };
    if !v.notes.is_empty() {
        s += "<p>Notes:</p>\n<ul>\n";
        for n in &v.notes {
            s += &format!("<li>{}</li>\n", escape(&n.describe(Spelling::Cli)));
        }
        s += "</ul>\n";
    }
    s
}

/// The χ² test, or the robust scale's test, or why there is none.
fn fit_quality(cal: &Calibration) -> String {
    if let Some(d) = cal.robust.as_ref().and_then(|r| r.describe_scale()) {
        return format!(
            "Fit quality (robust scale against the stated noise): {}",
            escape(&d)
        );
    }
    match &cal.checks.chi_square {
        Some(chi) => format!(
            "χ² test against the stated noise (each tail at {CHI_SQUARE_ALPHA}; refused beyond \
             {}): {}",
            power_of_ten(CHI_SQUARE_REFUSE),
            escape(&chi.describe())
        ),
        None => "χ² test: none — the noise was not stated, so σ was estimated from the fit's \
                 own residuals and cannot be tested against them (state the noise to test it)."
            .to_string(),
    }
}

/// The outliers by `file:line`, the first [`LISTED_OUTLIERS`].
fn outliers(cal: &Calibration) -> String {
    let o = &cal.checks.outliers;
    let beyond = cal.checks.outlier_threshold;
    if o.is_empty() {
        return format!("Outliers: none (no observation beyond {beyond:.2} σ).");
    }
    let listed: Vec<String> = (o.iter().take(LISTED_OUTLIERS))
        .map(|x| {
            format!(
                "<code>{}</code> (point {}, {:.1} σ)",
                escape(&x.at),
                escape(&x.point),
                x.standardised
            )
        })
        .collect();
    format!(
        "<span class=\"bad\">Outliers</span>: {} beyond {beyond:.2} σ — check them (remeasure, or \
         fix the label): {}{}.",
        o.len(),
        listed.join(", "),
        if o.len() > LISTED_OUTLIERS {
            format!(
                " and {} more (calibration.json lists them all)",
                o.len() - LISTED_OUTLIERS
            )
        } else {
            String::new()
        }
    )
}

/// One line per data set held out from the fit: its headline figure before
/// and after, or that none was held out.
fn held_out(rows: &[ValidationRow], input: &CalibrationInput) -> Vec<String> {
    let held: Vec<&ValidationRow> = rows.iter().filter(|r| r.held_out).collect();
    let terms = held_out_terms(input);
    if held.is_empty() && terms.is_empty() {
        return vec![
            "Held-out data: none (neither --validate nor --cross-validate): every figure after \
             calibration is on the data the fit used."
                .to_string(),
        ];
    }
    let lines = held.iter().map(|r| {
        let (b, a) = (r.figures.before.headline(), r.figures.after.headline());
        held_out_line(&r.name, r.figures.after.headline_name(), (b, a))
    });
    lines.chain(terms).collect()
}

/// `Held out, NAME: WHAT before → after mm`, the after good when not worse.
fn held_out_line(name: &str, what: &str, (b, a): (f64, f64)) -> String {
    let class = if a.is_finite() && a <= b {
        "good"
    } else {
        "bad"
    };
    format!(
        "Held out, {}: {what} {b:.4} → <span class=\"{class}\">{a:.4}</span> mm \
         (nominal → calibrated).",
        escape(name)
    )
}

/// The lines of the added terms' held-out observations: each fold's (RMS
/// of their errors) and a held-out sphere file's.
fn held_out_terms(input: &CalibrationInput) -> Vec<String> {
    let mut lines = Vec::new();
    for (i, f) in input.folds.iter().enumerate() {
        for t in &f.terms {
            let name = format!("fold {}, {} ({} held out)", i + 1, t.term, t.after.count);
            let what = "RMS |error|";
            lines.push(held_out_line(&name, what, (t.before.rms, t.after.rms)));
        }
    }
    if let Some(h) = input.held_out_spheres {
        let name = format!("{} ({} points on spheres)", h.file, h.after.count);
        let what = "RMS radial error (each sphere refitted)";
        lines.push(held_out_line(&name, what, (h.before.rms, h.after.rms)));
    }
    lines
}

/// A power of ten as 10 and a superscript exponent: 1e-9 → `10⁻⁹`.
fn power_of_ten(x: f64) -> String {
    let exponent = x.log10().round() as i32;
    let superscript = |c: char| match c {
        '-' => '⁻',
        d => ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'][d as usize - '0' as usize],
    };
    format!(
        "10{}",
        exponent
            .to_string()
            .chars()
            .map(superscript)
            .collect::<String>()
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn powers_of_ten_are_written_with_superscripts() {
        assert_eq!(super::power_of_ten(1e-9), "10⁻⁹");
        assert_eq!(super::power_of_ten(1e-10), "10⁻¹⁰");
        assert_eq!(super::power_of_ten(1e3), "10³");
    }
}
