//! The page of `aacmm verify --report DIR`: the acceptance tests' table
//! (test, value, MPE, U, decision, the calibration's prediction where
//! made) and each sphere placement's radial residuals, one strip per
//! placement in one figure.

use super::html::{escape, foot, head, section};
use super::{Figure, HTML_FILE, Report};
use crate::acceptance::{Acceptance, Use};

/// The figure of every placement's radial residuals.
pub const SPHERE_RESIDUALS_SVG: &str = "sphere_residuals.svg";

/// Every file `aacmm verify --report` writes, page first.
pub const ACCEPTANCE_FILES: [&str; 2] = [HTML_FILE, SPHERE_RESIDUALS_SVG];

/// The page and figure of `a`; `inputs` the files as the page lists them.
///
/// ```
/// # use aacmm_core::acceptance::*;
/// # use aacmm_core::report::{ACCEPTANCE_FILES, acceptance_report};
/// let a = Acceptance {
///     sphere_file: "s.csv".into(), sphere_diameter: 25.4, sphere_uncertainty: 0.0,
///     ball_diameter: 6.0, l_dia_radius: LDiaRadius::Held, mpe: Mpe::default(),
///     tests: vec![], untested: vec![], placements: vec![], l_dia: vec![], spat: vec![],
///     prediction: None,
/// };
/// let r = acceptance_report(&a, &[]);
/// let names: Vec<&str> = r.files().map(|(n, _)| n).collect();
/// assert_eq!(names, ACCEPTANCE_FILES);
/// assert!(r.html.contains("nothing is decided"));
/// ```
pub fn acceptance_report(a: &Acceptance, inputs: &[(String, String)]) -> Report {
    let figure = Figure {
        file: SPHERE_RESIDUALS_SVG,
        title: "Radial residuals per placement".into(),
        svg: strips(a),
    };
    let nav = [("tests", "1 Tests"), ("placements", "2 Placements")];
    let mut page = head(
        "Acceptance tests (ISO 10360-12 / ASME B89.4.22)",
        inputs,
        &nav,
    );
    let intro = format!(
        "Sphere {} mm (standard uncertainty {} mm), probe ball {} mm. A test is PASS when \
         |value| ≤ MPE − U, FAIL when |value| ≥ MPE + U, else INCONCLUSIVE (ISO 14253-1; U \
         expanded, k = 2). {}",
        a.sphere_diameter,
        a.sphere_uncertainty,
        a.ball_diameter,
        escape(a.outcome().trim())
    );
    page += &section(
        "tests",
        "1. Acceptance tests",
        &intro,
        None,
        "",
        "",
        &tests_table(a),
    );
    page += &section(
        "placements",
        "2. Sphere placements",
        "A least-squares sphere through every point of each placement (radius free); its \
         diameter as the sphere's surface, 2 (R_fit − r_ball).",
        Some(&figure),
        "Each strip: one placement's radial residuals |p − c| − R, one bar per point in the \
         file's order, on one scale for every placement.",
        "",
        &placements_table(a),
    );
    page += &foot(std::slice::from_ref(&figure));
    Report {
        html: page,
        figures: vec![figure],
    }
}

fn tests_table(a: &Acceptance) -> String {
    let mut t = String::from(
        "<table>\n<tr><th>test</th><th>at</th><th>value (mm)</th><th>MPE (mm)</th>\
         <th>U (mm)</th><th>decision</th><th>predicted (mm)</th></tr>\n",
    );
    for r in &a.tests {
        let mpe = r.mpe.map_or("–".to_string(), |m| format!("{m:.4}"));
        let decision = r.decision.map_or("not decided", |d| d.word());
        let predicted = r.predicted.map_or("–".to_string(), |p| {
            let seen = if p.agrees { "within 2σ" } else { "beyond 2σ" };
            format!("{:.4} ± {:.4} ({seen})", p.value, p.spread)
        });
        t += &format!(
            "<tr><td>{}</td><td>{}</td><td>{:.4}</td><td>{mpe}</td><td>{:.4}</td><td>{decision}</td><td>{predicted}</td></tr>\n",
            escape(&r.figure),
            escape(&r.at),
            r.value,
            r.u
        );
    }
    for u in &a.untested {
        t += &format!(
            "<tr><td>{}</td><td>–</td><td colspan=\"5\">an MPE is stated, no data tested it</td></tr>\n",
            u.key()
        );
    }
    t + "</table>\n"
}

fn placements_table(a: &Acceptance) -> String {
    let mut t = String::from(
        "<table>\n<tr><th>sphere</th><th>line</th><th>points</th><th>used for</th>\
         <th>diameter (mm)</th><th>σ (mm)</th><th>form (mm)</th></tr>\n",
    );
    for p in &a.placements {
        let used = match p.used_for {
            Use::Probing => "P_Size, P_Form",
            Use::Articulated => "L_Dia",
            Use::Length => "E_Uni",
        };
        t += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{used}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td></tr>\n",
            escape(&p.name),
            p.line,
            p.points,
            p.diameter,
            p.fit.diameter_sigma(),
            p.fit.form()
        );
    }
    t + "</table>\n"
}

/// One strip per placement: a bar per point's radial residual, on one
/// symmetric scale (the largest |residual|).
fn strips(a: &Acceptance) -> String {
    const W: f64 = 640.0;
    const ROW: f64 = 36.0;
    const LEFT: f64 = 90.0;
    let scale = (a.placements.iter())
        .flat_map(|p| p.fit.residuals.iter())
        .fold(0.0f64, |m, r| m.max(r.abs()))
        .max(1e-9);
    let h = 30.0 + ROW * a.placements.len().max(1) as f64;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{h}\" viewBox=\"0 0 {W} {h}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n\
         <text x=\"{LEFT}\" y=\"14\">radial residual, each strip ±{:.1} µm</text>\n",
        scale * 1000.0
    );
    for (k, p) in a.placements.iter().enumerate() {
        let mid = 30.0 + ROW * k as f64 + ROW / 2.0;
        s += &format!(
            "<text x=\"4\" y=\"{:.1}\">{}</text>\n<line x1=\"{LEFT}\" y1=\"{mid:.1}\" x2=\"{:.1}\" \
             y2=\"{mid:.1}\" stroke=\"#999\" stroke-width=\"0.5\"/>\n",
            mid + 4.0,
            escape(&p.name),
            W - 4.0
        );
        let n = p.fit.residuals.len().max(1) as f64;
        let step = (W - LEFT - 4.0) / n;
        for (i, r) in p.fit.residuals.iter().enumerate() {
            let len = r / scale * (ROW / 2.0 - 2.0);
            let (y, hgt) = if len >= 0.0 {
                (mid - len, len)
            } else {
                (mid, -len)
            };
            s += &format!(
                "<rect x=\"{:.1}\" y=\"{y:.2}\" width=\"{:.1}\" height=\"{hgt:.2}\" fill=\"#2b6cb0\"/>\n",
                LEFT + step * i as f64 + 0.15 * step,
                0.7 * step
            );
        }
    }
    s + "</svg>\n"
}
