//! The page: well-formed XHTML-compatible HTML (it parses as XML too), the
//! style inline, every figure inline as SVG; no script, no link to
//! anything outside the page.

use super::data::Evaluated;
use super::tables;
use super::{
    BEYOND_SVG, CalibrationInput, EvaluationInput, Figure, IDENTIFIABILITY_SVG, LENGTHS_SVG,
    PARAMETERS_SVG, POSITIONS_SVG, RESIDUALS_SVG, SINGLE_POINT_SVG, SOLVER_SVG,
    UNCERTAINTY_MAP_SVG,
};
use crate::calibrate::Calibration;
use crate::plan::UncertaintyMap;

/// Escapes `&`, `<`, `>`, `"` and `'` for HTML/XML text and attributes.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The style sheet: system fonts only, figures scale down with the window.
const STYLE: &str = "
body { font-family: system-ui, -apple-system, 'Segoe UI', Roboto, 'Helvetica Neue', Arial, sans-serif;
  color: #222; margin: 0 auto; padding: 0 20px 40px; max-width: 1440px; line-height: 1.4; }
h1 { font-size: 1.6em; margin: 18px 0 6px; }
h2 { font-size: 1.25em; margin: 30px 0 8px; padding-top: 10px; border-top: 2px solid #ddd; }
h3 { font-size: 1.0em; margin: 14px 0 4px; }
p { margin: 6px 0; max-width: 75em; }
nav { font-size: 0.95em; margin: 6px 0 10px; }
nav a { margin-right: 14px; color: #0072B2; }
.row { display: flex; flex-wrap: wrap; gap: 18px; align-items: flex-start; }
figure { margin: 0; flex: 0 1 900px; }
figure svg { max-width: 100%; height: auto; border: 1px solid #e4e4e4; }
figcaption { font-size: 0.92em; color: #444; margin-top: 4px; max-width: 960px; }
.side { flex: 1 1 400px; min-width: 320px; overflow-x: auto; }
table { border-collapse: collapse; margin: 6px 0 12px; font-size: 0.9em; }
caption { text-align: left; font-weight: 600; padding: 4px 0; }
th, td { border-bottom: 1px solid #e2e2e2; padding: 3px 8px; vertical-align: top; }
th { background: #f4f4f4; text-align: left; font-weight: 600; }
td.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.w { max-width: 30em; }
tr.after td { background: #f3f8fc; }
tr.held.after td { background: #fcf5f0; }
.inputs th { background: none; font-weight: 600; padding-left: 0; }
.note { color: #555; font-size: 0.92em; }
.bad { color: #b2182b; font-weight: 600; }
.good { color: #1b7837; font-weight: 600; }
footer { margin-top: 30px; font-size: 0.85em; color: #666; border-top: 1px solid #ddd; padding-top: 8px; }
";

/// An SVG document without anything a page cannot hold inline.
fn inline(svg: &str) -> &str {
    svg.trim_start_matches("<?xml version=\"1.0\" encoding=\"UTF-8\"?>")
        .trim()
}

/// The start of a page, through its heading and inputs.
pub(super) fn head(title: &str, inputs: &[(String, String)], nav: &[(&str, &str)]) -> String {
    let mut h = String::new();
    h += "<!DOCTYPE html>\n<html lang=\"en\" xmlns=\"http://www.w3.org/1999/xhtml\">\n<head>\n\
          <meta charset=\"utf-8\"/>\n\
          <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n";
    h += &format!("<title>{}</title>\n", escape(title));
    h += &format!("<style>{STYLE}</style>\n</head>\n<body>\n");
    h += &format!("<header>\n<h1>{}</h1>\n", escape(title));
    if !inputs.is_empty() {
        h += "<table class=\"inputs\">\n";
        for (k, v) in inputs {
            h += &format!("<tr><th>{}</th><td>{}</td></tr>\n", escape(k), escape(v));
        }
        h += "</table>\n";
    }
    h += "<nav>";
    for (id, name) in nav {
        h += &format!("<a href=\"#{id}\">{}</a>", escape(name));
    }
    h += "</nav>\n</header>\n";
    h
}

/// The end of a page: what wrote it and the figure files beside it.
pub(super) fn foot(figures: &[Figure]) -> String {
    let files: Vec<&str> = figures.iter().map(|f| f.file).collect();
    format!(
        "<footer>Written by aacmm {}. Every figure is also a file beside this page: {}. \
         Lengths in mm, angles in degrees; σ is a standard uncertainty (k = 1).</footer>\n\
         </body>\n</html>\n",
        env!("CARGO_PKG_VERSION"),
        escape(&files.join(", "))
    )
}

/// A section: heading, an introduction, the figure with its caption, and
/// what goes beside it (tables).
pub(super) fn section(
    id: &str,
    heading: &str,
    intro: &str,
    figure: Option<&Figure>,
    caption: &str,
    side: &str,
    below: &str,
) -> String {
    let mut s = format!("<section id=\"{id}\">\n<h2>{}</h2>\n", escape(heading));
    if !intro.is_empty() {
        s += &format!("<p>{intro}</p>\n");
    }
    s += "<div class=\"row\">\n";
    if let Some(f) = figure {
        s += &format!(
            "<figure>\n{}\n<figcaption>{caption} <span class=\"note\">(file {})</span></figcaption>\n</figure>\n",
            inline(&f.svg),
            escape(f.file)
        );
    }
    if !side.is_empty() {
        s += &format!("<div class=\"side\">\n{side}</div>\n");
    }
    s += "</div>\n";
    s += below;
    s += "</section>\n";
    s
}

/// The figure with file name `file`.
fn find<'a>(figures: &'a [Figure], file: &str) -> Option<&'a Figure> {
    figures.iter().find(|f| f.file == file)
}

/// Caption of figure 1.
const POINTS_CAPTION: &str = "Each marker is one point (cone socket): e = (1/n) Σ |x_i − x̄| over its n touches \
     (paper eq. 9–10). Grey: the arm before calibration; colour: after. Dots: points the fit used; \
     triangles: points held out from it. Dashed: the mean over the points, the paper's \
     single-point figure (1.873 → 0.127 mm in its experiment).";

/// Caption of figure 2.
const LENGTHS_CAPTION: &str = "Top: the paper's eq. 19 with absolute values for every pair of points, against the \
     distance of the pair's centroids (the printed eq. 19, without them, is of second order and \
     shown only in the table). Eq. 19 uses no reference length: it is repeatability seen again, \
     blind to scale. Bottom: the error of each calibrated reference length, |x̄_a − x̄_b| − L \
     (ISO 10360-12 E_Uni): the only test of scale. Before and after have panels of their own \
     because they differ by orders of magnitude.";

/// Caption of figure 5.
const RESIDUALS_CAPTION: &str = "How far each touch lies from its point's centroid, in bins of equal width on a log \
     scale, so that before and after share one axis. After a good calibration what remains is \
     the touch noise: one narrow hump, with no tail of outlying touches.";

/// The calibration report page: the verdict, the summary, then a section
/// per kind of evidence present — the 3-D errors at reference positions
/// first, the touch sections (single point, lengths, residuals) only with
/// touches — among those every calibration has (parameters,
/// identifiability, solver), and those of what it has besides.
pub(crate) fn calibration_page(
    input: &CalibrationInput,
    evaluated: &[Evaluated],
    figures: &[Figure],
) -> String {
    let cal = input.calibration;
    let json = input.calibration_json.as_deref();
    let present = Present {
        positions: !input.positions.is_empty(),
        touches: !evaluated.is_empty(),
        beyond: find(figures, BEYOND_SVG).is_some(),
        map: input.uncertainty_map.is_some(),
        spheres: input.spheres.is_some() || input.held_out_spheres.is_some(),
        tools: input.tools.is_some() || input.touch_tools.is_some(),
    };
    let numbered = present.sections();
    let number = |id: &str| {
        numbered
            .iter()
            .position(|(i, _)| *i == id)
            .map_or(0, |k| k + 1)
    };
    let mut nav: Vec<(&str, String)> = vec![
        ("verdict", "Verdict".to_string()),
        ("summary", "Summary".to_string()),
    ];
    nav.extend(
        (numbered.iter().enumerate()).map(|(k, (id, name))| (*id, format!("{} {name}", k + 1))),
    );
    let nav: Vec<(&str, &str)> = nav.iter().map(|(i, n)| (*i, n.as_str())).collect();
    let mut page = head(&input.title, &input.inputs, &nav);
    page += &super::verdict::section(input);
    page += &format!(
        "<section id=\"summary\">\n<h2>Summary</h2>\n{}{}</section>\n",
        tables::verdict(cal, evaluated, &input.arms, &input.validation),
        if present.touches {
            tables::glance(evaluated, &input.arms)
        } else {
            String::new()
        }
    );
    if present.positions {
        page += &positions_section(input, find(figures, POSITIONS_SVG), number("positions"));
    }
    if present.spheres {
        page += &sphere_sections(input, number("spheres"));
    }
    if present.tools {
        page += &tools_section(input.tools, input.touch_tools, number("tools"));
    }
    if present.touches {
        page += &touch_sections(input, evaluated, figures, number("single-point"));
    }
    page += &geometry_sections(input, figures, &number);
    if present.touches {
        page += &section(
            "residuals",
            &format!(
                "{}. Residuals per touch, before and after",
                number("residuals")
            ),
            "",
            find(figures, RESIDUALS_SVG),
            RESIDUALS_CAPTION,
            &tables::residuals(evaluated, &input.arms),
            "",
        );
    }
    page += &section(
        "solver",
        &format!("{}. Solver", number("solver")),
        "",
        find(figures, SOLVER_SVG),
        &solver_caption(present.touches),
        &tables::solver(cal, json),
        "",
    );
    if present.beyond {
        page += &beyond_section(cal, json, find(figures, BEYOND_SVG), number("beyond"));
    }
    if let Some(m) = input.uncertainty_map {
        let json = input.uncertainty_map_json.as_deref();
        page += &map_section(
            (
                m,
                input.uncertainty_maps_in_frames,
                input.uncertainty_maps_at_tools,
            ),
            json,
            find(figures, UNCERTAINTY_MAP_SVG),
            number("uncertainty-map"),
        );
    }
    page += &foot(figures);
    page
}

/// The sections every calibration has on its geometry: the parameters'
/// corrections and the identifiability, numbered as `number` says.
fn geometry_sections(
    input: &CalibrationInput,
    figures: &[Figure],
    number: &dyn Fn(&str) -> usize,
) -> String {
    let cal = input.calibration;
    let json = input.calibration_json.as_deref();
    let truths = super::figures::parameters::true_errors(cal, input.truth);
    section(
        "parameters",
        &format!(
            "{}. Parameters: corrections with ± 2σ",
            number("parameters")
        ),
        &tables::parameters_intro(cal),
        find(figures, PARAMETERS_SVG),
        "Correction = calibrated − nominal. Bars: ± 2σ (k = 2) from the covariance \
         σ̂0² (JᵀJ)⁻¹; a bar shorter than its dot is smaller than the dot's radius on this \
         scale (the table gives every σ). Crosses: parameters held at nominal, with the reason; \
         the data cannot determine them, so their errors are absorbed by the others.",
        "",
        &tables::parameters(cal, json, &truths),
    ) + &section(
        "identifiability",
        &format!("{}. Identifiability", number("identifiability")),
        "",
        find(figures, IDENTIFIABILITY_SVG),
        "Left: singular values of the weighted Jacobian with angle columns scaled by the reach \
         (an angle counts as the arc it sweeps there); below the threshold a direction is not \
         determined by the data and a parameter along it is fixed. Right: the correlation \
         coefficients ρ of the free parameters from the covariance; |ρ| > 0.9 is written in the \
         cell.",
        &tables::identification(cal, json),
        "",
    )
}

/// The kinds of evidence and results a calibration page has sections for.
struct Present {
    /// Reference positions (fitted or held out).
    positions: bool,
    /// Touches (fitted or held out).
    touches: bool,
    /// Models beyond geometry.
    beyond: bool,
    /// An uncertainty map.
    map: bool,
    /// Points probed on reference spheres.
    spheres: bool,
    /// Several tool points.
    tools: bool,
}

impl Present {
    /// The numbered sections in page order, as (id, name in the links).
    fn sections(&self) -> Vec<(&'static str, &'static str)> {
        let mut s = Vec::new();
        if self.positions {
            s.push(("positions", "3-D errors"));
        }
        if self.spheres {
            s.push(("spheres", "Sphere surfaces"));
        }
        if self.tools {
            s.push(("tools", "Tool points"));
        }
        if self.touches {
            s.extend([("single-point", "Single point"), ("lengths", "Lengths")]);
        }
        s.extend([
            ("parameters", "Parameters"),
            ("identifiability", "Identifiability"),
        ]);
        if self.touches {
            s.push(("residuals", "Residuals"));
        }
        s.push(("solver", "Solver"));
        if self.beyond {
            s.push(("beyond", "Beyond geometry"));
        }
        if self.map {
            s.push(("uncertainty-map", "Uncertainty map"));
        }
        s
    }
}

/// The solver figure's caption: the residuals the cost sums are those of
/// the evidence present.
fn solver_caption(touches: bool) -> String {
    let residuals = if touches {
        "touches against their centroids, reference lengths"
    } else {
        "reference positions against the registered arm"
    };
    format!(
        "Left: the cost Σr² of the weighted residuals ({residuals}) at each iteration of the \
         final Levenberg–Marquardt fit, from the start arm's cost (iteration 0; for hybrid and \
         global their search runs between 0 and 1); with the weights right it ends near m − p, \
         the degrees of freedom. Right: for the annealing methods (sa, hybrid), the energy of \
         the paper's SA (OA = e + 3σ, mm) as the temperature falls, and the share of moves \
         accepted at each temperature; for global, the cost each start ended at."
    )
}

/// The sections of a page with touches, numbered from `first` (after the
/// positions', spheres' and tools' sections when present): the
/// single-point errors and the length errors.
fn touch_sections(
    input: &CalibrationInput,
    evaluated: &[Evaluated],
    figures: &[Figure],
    first: usize,
) -> String {
    section(
        "single-point",
        &format!("{first}. Single-point error per point, before and after"),
        "",
        find(figures, SINGLE_POINT_SVG),
        POINTS_CAPTION,
        "",
        &tables::validation(&input.validation, &input.arms),
    ) + &section(
        "lengths",
        &format!("{}. Length errors, before and after", first + 1),
        "",
        find(figures, LENGTHS_SVG),
        LENGTHS_CAPTION,
        "",
        &(tables::lengths(evaluated, &input.arms)
            + &tables::references(evaluated, &input.arms, None)),
    )
}

/// The 3-D errors at the reference positions: the table (RMS, 95th
/// percentile, max per data set and arm, and per frame when there are
/// several) and the figure.
fn positions_section(input: &CalibrationInput, figure: Option<&Figure>, number: usize) -> String {
    section(
        "positions",
        &format!("{number}. 3-D errors at the reference positions, before and after"),
        "The distance |R p + t − y| between where each arm puts the probe (p, registered \
         into the instrument's frame by R, t) and where the instrument saw it (y). The nominal \
         arm's frames are registered to it in closed form on the fitted positions, the \
         calibrated arm's were fitted with it; a held-out frame is registered as the fitted \
         frame of its name — or, only where the user asked (--register-held-out) and then said \
         in its rows, on its own positions, which flatters the figures.",
        figure,
        "Left: the 3-D error of each pose against the probe's distance from the base axis. \
         Right: their distribution. Grey: the nominal arm; colour: the calibrated arm (blue on \
         the fitted positions, vermillion on held-out ones).",
        "",
        &(tables::positions(&input.validation, &input.positions, &input.arms)
            + &tables::orientations(&input.validation, &input.positions, &input.arms)),
    )
}

/// The points probed on reference spheres, numbered `number`: per sphere
/// its fitted centre and diameter, and the radial residuals before and
/// after (RMS, and their range: the form the arm sees).
fn spheres_section(
    s: &crate::session::spheres::SphereReport,
    input: &CalibrationInput,
    number: usize,
) -> String {
    let mut rows = String::new();
    for r in &s.spheres {
        let sigma = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.4}"));
        rows += &format!(
            "<tr><td>{}</td><td>{}</td><td>{:.3}, {:.3}, {:.3}</td><td>{}</td><td>{:.4}</td>\
             <td>{}</td><td>{:.4}</td><td class=\"after\">{:.4}</td><td>{:.4}</td>\
             <td class=\"after\">{:.4}</td></tr>\n",
            escape(&r.name),
            r.points,
            r.centre[0],
            r.centre[1],
            r.centre[2],
            sigma(
                r.centre_sigma
                    .map(|v| v.iter().fold(0.0, |a: f64, b| a.max(*b)))
            ),
            r.diameter,
            sigma(r.diameter_sigma),
            r.before.rms,
            r.after.rms,
            r.before.form,
            r.after.form
        );
    }
    let table = format!(
        "<table>\n<tr><th>sphere</th><th>points</th><th>centre (mm)</th><th>σ (largest)</th>\
         <th>diameter (mm)</th><th>σ</th><th>RMS radial, nominal</th><th>calibrated</th>\
         <th>form, nominal</th><th>calibrated</th></tr>\n{rows}</table>\n"
    );
    let size = match s.stated_diameter {
        Some(d) => format!("the spheres' diameter is stated ({d} mm) and fixes the arm's size"),
        None => "each sphere's diameter is fitted, so the spheres alone do not fix the arm's \
                 size"
            .to_string(),
    };
    section(
        "spheres",
        &format!("{number}. Sphere surfaces: radial residuals, before and after"),
        &format!(
            "Points probed on reference spheres ({}; probe ball {} mm): each residual is the \
             distance of the probe ball's centre from the sphere's fitted centre less the two \
             radii; {size}. The form is the range of a sphere's radial residuals. Before: the \
             nominal arm with each sphere fitted to it; after: the calibrated arm.",
            escape(&s.file),
            s.ball_diameter
        ),
        None,
        "",
        "",
        &(table
            + &held_out_spheres(input.folds)
            + &input
                .held_out_spheres
                .map_or_else(String::new, held_out_sphere_file)),
    )
}

/// A held-out sphere file's table: per sphere its diameter and radial
/// residuals, each arm's sphere refitted on the points with the arm fixed.
fn held_out_sphere_file(h: &crate::session::spheres::HeldOutSpheres) -> String {
    let mut rows = String::new();
    for s in &h.spheres {
        rows += &format!(
            "<tr><td>{}</td><td>{}</td><td>{:.4}</td><td class=\"after\">{:.4}</td>\
             <td>{:.4}</td><td class=\"after\">{:.4}</td><td>{:.4}</td>\
             <td class=\"after\">{:.4}</td></tr>\n",
            escape(&s.name),
            s.points,
            s.diameter_before,
            s.diameter_after,
            s.before.rms,
            s.after.rms,
            s.before.form,
            s.after.form
        );
    }
    let diameter = match h.stated_diameter {
        Some(d) => format!("its diameter held at the stated {d} mm"),
        None => "its diameter refitted too".to_string(),
    };
    format!(
        "<p>Held out ({}): each sphere's centre refitted on its own points with the arm held \
         fixed, {diameter}; every point's |radial error| RMS {:.4} mm nominal, {:.4} mm \
         calibrated (p95 {:.4} / {:.4} mm).</p>\n<table>\n<tr><th>sphere</th><th>points</th>\
         <th>diameter, nominal</th><th>calibrated</th><th>RMS radial, nominal</th>\
         <th>calibrated</th><th>form, nominal</th><th>calibrated</th></tr>\n{rows}</table>\n",
        escape(&h.file),
        h.before.rms,
        h.after.rms,
        h.before.p95,
        h.after.p95
    )
}

/// The points on spheres each cross-validation fold held out: their
/// `|radial error|` before and after, per fold; empty without them.
fn held_out_spheres(folds: &[crate::calibrate::validate::Fold]) -> String {
    let mut rows = String::new();
    let mut what = "";
    for (i, f) in folds.iter().enumerate() {
        let of = |t: &&crate::calibrate::validate::TermHeldOut| {
            t.term == crate::residuals::spheres::TERM
        };
        for t in f.terms.iter().filter(of) {
            what = &t.what;
            for (name, e) in [("before", &t.before), ("after", &t.after)] {
                rows += &format!(
                    "<tr><td>fold {} ({name})</td><td>{}</td>\
                     <td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td></tr>\n",
                    i + 1,
                    e.count,
                    e.mean,
                    e.rms,
                    e.p95,
                    e.max
                );
            }
        }
    }
    if rows.is_empty() {
        return String::new();
    }
    format!(
        "<p>Cross-validation: held-out {} (mm).</p>\n<table>\n<tr><th>fold</th><th>points</th>\
         <th>mean</th><th>RMS</th><th>p95</th><th>max</th></tr>\n{rows}</table>\n",
        escape(what)
    )
}

/// The spheres' section, numbered `number`: the fitted spheres' (with the
/// held-out file's table when given), else the held-out file's alone.
fn sphere_sections(input: &CalibrationInput, number: usize) -> String {
    match (input.spheres, input.held_out_spheres) {
        (Some(s), _) => spheres_section(s, input, number),
        (None, Some(h)) => section(
            "spheres",
            &format!("{number}. Sphere surfaces held out"),
            "",
            None,
            "",
            "",
            &held_out_sphere_file(h),
        ),
        (None, None) => String::new(),
    }
}

/// The tool points, numbered `number`: per tool its offset ± σ and its
/// rows' error RMS before and after, a table for the positions' tools and
/// one for the touches', each when present.
fn tools_section(
    positions: Option<&crate::session::tools::ToolReport>,
    touches: Option<&crate::session::tools::ToolReport>,
    number: usize,
) -> String {
    let mut words = String::new();
    let mut tables = String::new();
    if let Some(t) = positions {
        words += &format!(
            "The tool points the rows of {} name (markers, SMRs, styli: the arm file's \
             [[tool]]), each offset in the last joint's frame and fitted with the arm; `{}` is \
             the arm's probe. RMS of each tool's rows' 3-D errors |R p + t − y|: before, the \
             nominal arm with its nominal offsets; after, the calibrated arm.",
            escape(&t.file),
            crate::domain::DEFAULT_TOOL
        );
        tables += &tool_table(t, "RMS 3-D, nominal");
    }
    if let Some(t) = touches {
        if !words.is_empty() {
            words += " ";
        }
        words += &format!(
            "The probes the touches of {} name (the arm file's [[tool]]; `{}` is the arm's \
             probe), each offset in the last joint's frame and fitted with the arm. RMS of each \
             probe's touches' distances from their points' centres (the mean of each point's \
             touches): before, the nominal arm with its nominal offsets; after, the calibrated \
             arm.",
            escape(&t.file),
            crate::domain::DEFAULT_TOOL
        );
        tables += &tool_table(t, "RMS from the centre, nominal");
    }
    section(
        "tools",
        &format!(
            "{number}. Tool points: offsets and {}errors per tool",
            if touches.is_some() { "" } else { "3-D " }
        ),
        &words,
        None,
        "",
        "",
        &tables,
    )
}

/// One tool report's table, its RMS column before calibration headed
/// `before`.
fn tool_table(t: &crate::session::tools::ToolReport, before: &str) -> String {
    let mut rows = String::new();
    for r in &t.tools {
        let three = |v: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", v[0], v[1], v[2]);
        rows += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.4}</td>\
             <td class=\"after\">{:.4}</td></tr>\n",
            escape(&r.name),
            r.rows,
            three(r.nominal),
            three(r.offset),
            r.sigma.map_or("held".to_string(), three),
            r.rms_before,
            r.rms_after
        );
    }
    format!(
        "<table>\n<tr><th>tool</th><th>rows</th><th>nominal offset (mm)</th>\
         <th>fitted offset (mm)</th><th>σ (mm, k = 1)</th><th>{before}</th>\
         <th>calibrated</th></tr>\n{rows}</table>\n"
    )
}

/// The models beyond geometry, their table and figure, numbered `number`.
fn beyond_section(
    cal: &Calibration,
    json: Option<&str>,
    figure: Option<&Figure>,
    number: usize,
) -> String {
    section(
        "beyond",
        &format!("{number}. Beyond geometry"),
        "Models the fit estimated with the geometry: each column's value with its σ, or why \
         the data could not separate it (it is then held at its stated value).",
        figure,
        "Per fitted pose, how far each model's fitted correction alone moves the calibrated \
         arm's probe: the error it explains. Part of it a geometric parameter can mimic (a \
         compliance partly acts as a zero offset: see the correlations), so this bounds from \
         above what a geometric fit would have left in the residuals or spread over the \
         parameters.",
        "",
        &tables::beyond(cal, json),
    )
}

/// The uncertainty map's section, numbered `number`: what the radius is
/// in one plain sentence, the figure and the table per band — and one per
/// fitted frame (`maps.1`), as its instrument sees the probe, and one per
/// fitted tool point (`maps.2`).
fn map_section(
    (map, in_frames, at_tools): (&UncertaintyMap, &[UncertaintyMap], &[UncertaintyMap]),
    json: Option<&str>,
    figure: Option<&Figure>,
    number: usize,
) -> String {
    let percent = 100.0 * map.coverage;
    // Stated because a 3-D error needs 2.80 σ, and readers expect the 2 σ
    // of one coordinate.
    let intro = format!(
        "The radius that holds the calibrated probe position's error with {percent:.0} % \
         probability ({k:.2} σ for an isotropic 3-D error, not 2 σ), over {n} poses sampled \
         within {w}: RMS {rms:.4} mm, median {median:.4} mm, largest {max:.4} mm. It comes \
         from the covariance of the fitted geometry alone (J C Jᵀ at each pose): the error \
         of the calibrated model's prediction there; a single touch adds its own probe \
         noise on top.",
        k = map.k_isotropic,
        n = map.poses,
        w = escape(&map.workspace),
        rms = map.rms_mm,
        median = map.median_mm,
        max = map.max_mm,
    );
    section(
        "uncertainty-map",
        &format!("{number}. Predicted position uncertainty over the workspace"),
        &intro,
        figure,
        &format!(
            "Each dot is one sampled pose ({shown}): its {percent:.0} % radius against the \
             probe's distance from the shoulder — the base axis at the first joint's height — \
             coloured by the probe's height above the shoulder. The line is the RMS of the \
             radius per band of that distance, as in the table.",
            shown = if map.points.len() == map.poses {
                format!("all {}", map.poses)
            } else {
                format!("{} of the {}, evenly spread", map.points.len(), map.poses)
            }
        ),
        &tables::uncertainty_map(map, json),
        &(frame_maps(in_frames, json) + &tool_maps(at_tools, json)),
    )
}

/// Per fitted tool point, its map's numbers in a sentence and its table:
/// the offset's own uncertainty is part of what that tool measures.
fn tool_maps(maps: &[UncertaintyMap], json: Option<&str>) -> String {
    let words = |name: &str| {
        format!(
            "At the tool point <code>{name}</code> (its fitted offset in place of the probe's), \
             the same poses' radius includes the offset's uncertainty, fitted with the arm (J C \
             Jᵀ over the geometry and the offset's three columns together)"
        )
    };
    map_tables(
        maps,
        json,
        "/uncertainty_maps_at_tools",
        |m| m.tool.as_deref(),
        words,
    )
}

/// Per fitted frame, its map's numbers in a sentence and its table: the
/// frame's registration error is part of what that instrument sees.
fn frame_maps(maps: &[UncertaintyMap], json: Option<&str>) -> String {
    let words = |name: &str| {
        format!(
            "As the instrument of frame <code>{name}</code> sees the probe, the same poses' \
             radius includes that frame's registration, fitted with the arm (J C Jᵀ over the \
             geometry and the frame's six columns together)"
        )
    };
    map_tables(
        maps,
        json,
        "/uncertainty_maps_in_frames",
        |m| m.frame.as_deref(),
        words,
    )
}

/// Per map of `maps`, a sentence (`words` of its escaped `name`, then its
/// figures) and its table, its JSON Pointer `pointer/<i>`.
fn map_tables(
    maps: &[UncertaintyMap],
    json: Option<&str>,
    pointer: &str,
    name: impl Fn(&UncertaintyMap) -> Option<&str>,
    words: impl Fn(&str) -> String,
) -> String {
    let mut out = String::new();
    for (i, m) in maps.iter().enumerate() {
        out += &format!(
            "<p>{}: RMS {rms:.4} mm, median {median:.4} mm, largest {max:.4} mm.</p>\n",
            words(&escape(name(m).unwrap_or_default())),
            rms = m.rms_mm,
            median = m.median_mm,
            max = m.max_mm,
        );
        let at = json.map(|_| format!("{pointer}/{i}"));
        out += &tables::uncertainty_map(m, at.as_deref());
    }
    out
}

/// The evaluation report page.
pub(crate) fn evaluation_page(
    input: &EvaluationInput,
    evaluated: &[Evaluated],
    figures: &[Figure],
) -> String {
    let json = input.evaluation_json.as_deref();
    let nav = [
        ("single-point", "1 Single point"),
        ("lengths", "2 Lengths"),
        ("residuals", "3 Residuals"),
    ];
    let arms = super::Arms {
        before: String::new(),
        after: input.arm.clone(),
    };
    let beyond = find(figures, BEYOND_SVG);
    let mut nav = nav.to_vec();
    if beyond.is_some() {
        nav.push(("beyond", "7 Beyond geometry"));
    }
    let mut page = head(&input.title, &input.inputs, &nav);
    let e = &evaluated[0];
    page += &section(
        "single-point",
        "1. Single-point error per point",
        "",
        find(figures, SINGLE_POINT_SVG),
        "Each marker is one point (cone socket): e = (1/n) Σ |x_i − x̄| over its n touches \
         (paper eq. 9–10); dashed: the mean over the points (the paper's Fig. 6 figure).",
        &tables::points_summary(e, json),
        &tables::points(e, json),
    );
    page += &section(
        "lengths",
        "2. Length errors",
        "",
        find(figures, LENGTHS_SVG),
        "Top: the paper's eq. 19 with absolute values for every pair of points, against the \
         distance of the pair's centroids; eq. 19 uses no reference length and cannot see \
         scale. Bottom: the error of each reference length, |x̄_a − x̄_b| − L (ISO 10360-12 \
         E_Uni), the only test of scale.",
        "",
        &(tables::lengths(evaluated, &arms) + &tables::references(evaluated, &arms, json)),
    );
    page += &section(
        "residuals",
        "3. Residuals per touch",
        "",
        find(figures, RESIDUALS_SVG),
        RESIDUALS_CAPTION,
        &tables::residuals(evaluated, &arms),
        "",
    );
    page += &foot(figures);
    page
}

#[cfg(test)]
mod tests {
    #[test]
    fn escape_covers_the_five_markup_characters() {
        assert_eq!(
            super::escape("a<b & \"c\" 'd'>"),
            "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;"
        );
    }
}
