//! The text summary every front end prints.

use crate::calibrate::Calibration;
use crate::calibrate::validate::Figures;

use crate::session::{CalibrationReport, Note, Spelling, Validation, Verdict, noun, outliers_noun};

impl CalibrationReport {
    /// The summary every front end prints: the solver, the dof, every
    /// parameter with σ, the correlations and the validation table.
    pub fn summary(&self) -> String {
        let c = &self.calibration;
        let mut t = self.summary_header();
        t += &dof_lines(c);
        t += &fit_quality_lines(c);
        let maps = self
            .uncertainty_map
            .iter()
            .chain(&self.uncertainty_maps_in_frames)
            .chain(&self.uncertainty_maps_at_tools);
        for m in maps {
            t += &format!("Uncertainty map: {}\n", m.describe());
        }
        t += &outliers_line(c);
        t += &verdict_line(&self.verdict);
        t += &joints_line(c);
        t += &parameter_table(c);
        t += &correlations_line(c);
        t += &validation_table(&self.validation);
        if let Some(s) = &self.spheres {
            t += &s.summary();
        }
        if let Some(h) = &self.validation.held_out_spheres {
            t += &h.summary();
        }
        for s in self.tools.iter().chain(&self.touch_tools) {
            t += &s.summary();
        }
        t
    }

    /// The orientation noise the tool orientations were weighed with, in
    /// words; `None` without reference positions or a stated σ (only a file
    /// with orientations is weighed by it: without one the fit refuses
    /// them).
    pub(crate) fn orientation_noise(&self) -> Option<String> {
        let o = self.noise.orientation_rad?;
        self.positions_file.as_ref()?;
        Some(format!(
            "stated: σ = {}° per axis (the rows giving the tool's orientation)",
            // Rounded: the degrees given, not their trip through rad.
            (o.to_degrees() * 1e9).round() / 1e9
        ))
    }

    /// The reference positions' noise, `None` without them: the σ stated
    /// (`--position-noise`, or each row's own), or that it was estimated,
    /// with the σ the fit used; and an encoder noise stated without
    /// touches, which weighs nothing.
    pub(crate) fn position_noise(&self) -> Option<String> {
        let r = self;
        r.positions_file.as_ref()?;
        let n = r.noise;
        let d = &r.calibration.dof;
        let mut s = match (n.position_mm, n.position_mm_per_m) {
            (Some(a), Some(b)) if b > 0.0 => format!(
                "stated: σ = {a} mm + {b} mm per metre from the instrument, per coordinate (where \
                 a row states no uncertainty of its own)"
            ),
            (Some(a), _) => format!(
                "stated: σ = {a} mm per coordinate (where a row states no uncertainty of its own)"
            ),
            // Alone, positions are weighed as stated only by their own column.
            (None, _) if r.touches == 0 && !d.touch_sigma_estimated => {
                "stated: each row's own uncertainty (the file's `uncertainty` column)".to_string()
            }
            // The σ's source follows ("estimated from the fit").
            (None, _) if r.touches == 0 => "not stated".to_string(),
            (None, _) => "no --position-noise: each row's own uncertainty where the file states \
                          one, else a σ estimated from the fit"
                .to_string(),
        };
        let noun = if r.touches > 0 {
            "observation"
        } else {
            "position"
        };
        s += &format!(
            "; the fit's {noun} σ {:.4} mm ({})",
            d.touch_sigma_mm,
            if d.touch_sigma_estimated {
                "estimated from the fit"
            } else {
                "from the stated noise"
            }
        );
        if let (Some(e), 0) = (n.encoder_rad, r.touches) {
            s += &format!(
                "; encoders {} deg stated, weighing no row: a position's σ is the instrument's",
                e.to_degrees()
            );
        }
        Some(s)
    }

    /// The summary's head: what was calibrated on what, and how the solver
    /// went.
    fn summary_header(&self) -> String {
        let r = self;
        let s = &r.calibration.solver;
        let mut t = if r.touches == 0 {
            String::new()
        } else {
            format!(
                "calibrated `{}` ({}) on {}: {} touches of {} points, {} reference lengths\n",
                r.arm, r.arm_file, r.data_file, r.touches, r.points, r.reference_lengths
            )
        };
        if let Some(file) = &r.positions_file {
            let frames = r.calibration.frames().len();
            t += &format!(
                "calibrated `{}` ({}) on {file}: {} reference positions in {frames} frame{}\n",
                r.arm,
                r.arm_file,
                r.positions,
                if frames == 1 { "" } else { "s" }
            );
        }
        if let Some(noise) = r.position_noise() {
            t += &format!("Position noise: {noise}\n");
        }
        if let Some(noise) = r.orientation_noise() {
            t += &format!("Orientation noise: {noise}\n");
        }
        t += "\n";
        t += &method_lines(s);
        t += &format!(
            "Solver: {} — {} after {} iterations ({} cost and {} Jacobian evaluations); \
             cost {:.6e} -> {:.6e}\n",
            s.method.name(),
            s.stop.describe(),
            s.iterations,
            s.cost_evaluations,
            s.jacobian_evaluations,
            s.initial_cost,
            s.final_cost
        );
        t
    }
}

/// The summary's degrees of freedom and the σ behind the weights.
fn dof_lines(c: &Calibration) -> String {
    let d = &c.dof;
    let mut t = if d.touch_rows == 0 && d.length_rows == 0 {
        let included = match (d.rows_of("positions") > 0, d.rows_of("spheres") > 0) {
            (false, true) => "the spheres' included",
            (true, true) => "the frames' and the spheres' included",
            _ => "the frames' included",
        };
        format!(
            "Residuals: {} rows; unknowns: {} parameters ({included}); {} degrees of freedom\n",
            d.other_rows.iter().map(|r| r.rows).sum::<usize>(),
            d.free_parameters,
            d.degrees_of_freedom
        )
    } else {
        format!(
            "Residuals: {} touch rows + {} length rows; unknowns: {} parameters + {} centre \
             coordinates; {} degrees of freedom\n",
            d.touch_rows,
            d.length_rows,
            d.free_parameters,
            d.centre_coordinates,
            d.degrees_of_freedom
        )
    };
    t += &format!(
        "sigma0 = {} = {:.4} (1 when the weights are right); {} sigma {:.4} mm{}\n",
        if c.robust.is_some() {
            "robust scale (median of the standardised residuals)"
        } else {
            "sqrt(cost/dof)"
        },
        d.sigma0,
        noun(c),
        d.touch_sigma_mm,
        if d.touch_sigma_estimated {
            " (estimated from the fit)"
        } else {
            " (from the stated noise)"
        }
    );
    if !d.other_rows.is_empty() {
        let terms: Vec<String> = (d.other_rows.iter())
            .map(|r| format!("{} {} rows ({} eliminated)", r.term, r.rows, r.eliminated))
            .collect();
        t += &format!("Other residual terms (in the dof): {}\n", terms.join(", "));
    }
    t
}

/// The summary's account of the fit against the noise: the prior, the χ²
/// test, the robust fit and what the experiment can determine.
fn fit_quality_lines(c: &Calibration) -> String {
    let mut t = String::new();
    if let Some(p) = &c.prior {
        t += &format!(
            "Prior: {}; {} pseudo-observation rows (counted in the dof), prior cost {:.3}{}\n",
            p.tolerances,
            p.rows,
            p.cost,
            p.conflict().unwrap_or_default()
        );
        if !p.carried.is_empty() {
            let what: Vec<String> = p.carried.iter().map(|c| c.describe()).collect();
            t += &format!(
                "Tolerances carried onto the free partners of redundant fixed parameters (the data \
                 see only their sums; in quadrature): {}\n",
                what.join("; ")
            );
        }
    }
    if let Some(chi) = &c.checks.chi_square {
        t += &format!("Fit quality: {}\n", chi.describe());
    }
    if let Some(r) = &c.robust {
        if let Some(d) = r.describe_scale() {
            t += &format!("Fit quality: {d}\n");
        }
        t += &robust_line(r, noun(c));
    }
    if let Some(u) = &c.checks.position_uncertainty {
        t += &format!("Experiment: {}\n", u.describe());
    }
    if let Some(s) = Note::scale(c) {
        t += &format!("Scale: {}\n", s.describe(Spelling::Cli));
    }
    t
}

/// `noun`, counted: `touch(es)`, `position(s)`.
fn plural(noun: &str) -> String {
    match noun {
        "touch" => "touch(es)".to_string(),
        _ => format!("{noun}(s)"),
    }
}

/// [`noun`], or `observation` when orientations are observed too.
fn any_noun(c: &Calibration) -> &'static str {
    match c.dof.rows_of("orientations") > 0 {
        true => "observation",
        false => noun(c),
    }
}

/// The summary's outliers: the first 20 by `file:line`; after a screen by
/// a robust refit, that the list keeps to the touches it weighs down, and
/// how many the plain fit had beyond the threshold.
fn outliers_line(c: &Calibration) -> String {
    let o = &c.checks.outliers;
    let noun = any_noun(c);
    let threshold = c.checks.outlier_threshold;
    let screen = c.checks.outlier_screen;
    let below = crate::calibrate::robust::DOWNWEIGHTED;
    if o.is_empty() {
        return match screen {
            Some(s) => format!(
                "Outliers: none singled out: {} {} beyond {threshold:.2} sigma, none of which a \
                 robust {} refit weighs below {below} — the residuals are large overall, not a \
                 few {}\n",
                s.flagged,
                plural(noun),
                s.loss.name(),
                plural(noun)
            ),
            None => format!("Outliers: none (no {noun} beyond {threshold:.2} sigma)\n"),
        };
    }
    let shown: Vec<String> = o
        .iter()
        .take(20)
        .map(|x| {
            let kind = x.kind.as_ref().map_or(String::new(), |k| format!("{k}, "));
            format!(
                "{} (point {}, {kind}{:.1} sigma)",
                x.at, x.point, x.standardised
            )
        })
        .collect();
    let screened = screen.map_or(String::new(), |s| {
        // What the screen says of the rest: pulled by the named touches,
        // or (far outside the stated noise all the same) a wrong minimum
        // or model; else nothing.
        let far = (c.checks.chi_square.as_ref()).is_some_and(|chi| chi.far_outside());
        let why = if s.explains(c.dof.sigma0) {
            ", pulled by them"
        } else if far {
            ", and the rest stay large without them: a wrong minimum or model"
        } else {
            ""
        };
        format!(
            " that a robust {} refit weighs below {below} (of {} beyond it in this fit{why})",
            s.loss.name(),
            s.flagged
        )
    });
    format!(
        "Outliers: {} {} beyond {threshold:.2} sigma{screened} — check them (remeasure, or \
         fix the label): {}{}\n",
        o.len(),
        plural(outliers_noun(o, self::noun(c))),
        shown.join(", "),
        if o.len() > shown.len() { ", …" } else { "" }
    )
}

/// The summary's parameter table (user units), and the prior's if any.
/// The chain's joints with their types and reading units, when some joint
/// slides (a revolute arm's summary is what it always was).
///
/// ```text
/// Joints: 1 prismatic (reading mm), 2 revolute (reading deg), …
/// ```
fn joints_line(c: &Calibration) -> String {
    use crate::params::JointKind;
    if !c.joint_types.contains(&JointKind::Prismatic) {
        return String::new();
    }
    let joints: Vec<String> = (c.joint_types.iter().enumerate())
        .map(|(j, k)| format!("{} {} (reading {})", j + 1, k.name(), k.reading_unit()))
        .collect();
    format!("Joints: {}\n", joints.join(", "))
}

fn parameter_table(c: &Calibration) -> String {
    let mut t = String::from("Parameters (mm, deg; sigma = standard uncertainty, k = 1):\n");
    t += &format!(
        "  {:<8} {:<4} {:>14} {:>14} {:>12} {:>10}  {}\n",
        "name", "unit", "nominal", "calibrated", "correction", "sigma", "fixed because"
    );
    for p in c.parameters.iter().map(|p| p.user()) {
        t += &format!(
            "  {:<8} {:<4} {:>14.6} {:>14.6} {:>12.6} {:>10}  {}\n",
            p.name,
            p.unit,
            p.nominal,
            p.calibrated,
            p.correction,
            p.sigma.map_or("-".to_string(), |s| format!("{s:.6}")),
            p.fixed.as_deref().unwrap_or("")
        );
    }
    if let Some(p) = &c.prior {
        t += &prior_table(p);
    }
    if !c.auxiliary.is_empty() {
        t += if c.auxiliary.iter().any(|e| e.fixed.is_some()) {
            "Auxiliary blocks (sigma k = 1; a correction the data cannot separate is held):\n"
        } else {
            "Auxiliary blocks (every column free; sigma k = 1):\n"
        };
        // The unit column as wide as its widest unit (`µrad/(N·m)`).
        let w = (c.auxiliary.iter())
            .map(|e| e.unit.chars().count())
            .fold(4, usize::max);
        t += &format!(
            "  {:<16} {:<w$} {:>14} {:>14} {:>10}\n",
            "name", "unit", "start", "calibrated", "sigma"
        );
        for e in &c.auxiliary {
            // Why a column was held, or what its σ is of when not its
            // value (a frame's rotation: a small rotation about an axis).
            let note = match (&e.fixed, &e.sigma_of) {
                (Some(why), _) => why.clone(),
                (None, Some(of)) if e.sigma.is_some() => format!("sigma of {of}"),
                _ => String::new(),
            };
            let line = format!(
                "  {:<16} {:<w$} {:>14.6} {:>14.6} {:>10}  {note}",
                e.name,
                e.unit,
                e.start,
                e.calibrated,
                e.sigma.map_or("-".to_string(), |s| format!("{s:.6}")),
            );
            t += line.trim_end();
            t += "\n";
        }
    }
    t
}

fn correlations_line(c: &Calibration) -> String {
    if c.correlations.is_empty() {
        return "No pair of free parameters correlates with |rho| > 0.9.\n".to_string();
    }
    let mut t = String::from("Correlations |rho| > 0.9:");
    for x in &c.correlations {
        t += &format!("  {}/{} {:+.3}", x.a, x.b, x.rho);
    }
    t += "\n";
    t += &held_lines(c);
    t
}

/// The weak directions held at nominal, one line each, with the remedy.
fn held_lines(c: &Calibration) -> String {
    if c.held.is_empty() {
        return String::new();
    }
    let mut t = format!(
        "Held at nominal: {} direction(s) the data determine more than {:.0} times worse than the \
         best one (fitted, they would follow noise and model error; state tolerances for their \
         parameters — `[prior]` or --prior — to fit them):\n",
        c.held.len(),
        1.0 / crate::residuals::WEAK_RATIO
    );
    for h in &c.held {
        t += &format!("  {}\n", h.describe());
    }
    t
}

/// The summary's validation table: before and after, on the fitted data,
/// the held-out data and each cross-validation fold.
fn validation_table(v: &Validation) -> String {
    if v.fitted.before.points == 0
        && v.held_out
            .as_ref()
            .is_none_or(|h| h.figures.before.points == 0)
    {
        return position_table(v) + "\n";
    }
    let mut t = String::from(
        "\nValidation (mm): e = mean single-point error, 2s and delta_max (SPAT), length RMS/max\n",
    );
    t += &format!(
        "  {:<28} {:>8} {:>8} {:>9} {:>10} {:>10}\n",
        "data", "e", "2s", "delta_max", "len RMS", "len max"
    );
    let mut row = |name: &str, f: &Figures| {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        t += &format!(
            "  {:<28} {:>8.4} {:>8.4} {:>9.4} {:>10} {:>10}\n",
            name,
            f.e_mean,
            f.two_s_mean,
            f.delta_max,
            opt(f.length_rms),
            opt(f.length_max)
        );
    };
    row("fitted, before", &v.fitted.before);
    row("fitted, after", &v.fitted.after);
    if let Some(h) = &v.held_out {
        row("held out, before", &h.figures.before);
        row("held out, after", &h.figures.after);
    }
    if let Some(cv) = &v.cross_validation {
        for (i, f) in cv.folds.iter().enumerate() {
            row(
                &format!("fold {} ({} pts), before", i + 1, f.held_out.len()),
                &f.figures.before,
            );
            row(
                &format!("fold {} ({} pts), after", i + 1, f.held_out.len()),
                &f.figures.after,
            );
        }
    }
    t += &position_table(v);
    t += "\n";
    t
}

/// The validation at the reference positions, if any: the 3-D distance
/// between where each arm (its frames registered) puts the probe and where
/// the instrument saw it.
fn position_table(v: &Validation) -> String {
    let mut rows: Vec<(String, &Figures)> = vec![
        ("fitted, before".into(), &v.fitted.before),
        ("fitted, after".into(), &v.fitted.after),
    ];
    if let Some(h) = &v.held_out {
        rows.push(("held out, before".into(), &h.figures.before));
        rows.push(("held out, after".into(), &h.figures.after));
    }
    for (i, fold) in v
        .cross_validation
        .iter()
        .flat_map(|cv| &cv.folds)
        .enumerate()
    {
        rows.push((format!("fold {}, before", i + 1), &fold.figures.before));
        rows.push((format!("fold {}, after", i + 1), &fold.figures.after));
    }
    let mut t = error_table(
        &rows,
        |f| f.positions,
        "\nReference positions (mm): 3-D error |R p + t - y| per pose\n",
    );
    if let Some(h) = v
        .held_out
        .as_ref()
        .filter(|h| !h.registered_on_itself.is_empty())
    {
        t += &format!(
            "  held out: {} not fitted, registered on its own positions as asked \
             (--register-held-out): these held-out figures are optimistic\n",
            h.registered_on_itself
                .iter()
                .map(|f| format!("frame `{f}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    t += &error_table(
        &rows,
        |f| f.orientations,
        "\nTool orientations (deg): angle of the turn from the arm's tool frame to the one \
         seen, per pose\n",
    );
    t += &term_tables(v);
    t
}

/// The rows of `rows` whose figures have the errors `of` picks, under
/// `title` and a header; empty when none has them.
fn error_table(
    rows: &[(String, &Figures)],
    of: impl Fn(&Figures) -> Option<crate::calibrate::validate::PositionErrors>,
    title: &str,
) -> String {
    let rows = (rows.iter()).filter_map(|(name, f)| of(f).map(|p| (name.clone(), p)));
    errors_table(rows, title, "poses")
}

/// The held-out observations of each added term the folds scored (points
/// on spheres): a table per term, its `|error|` before and after per fold;
/// empty without any.
fn term_tables(v: &Validation) -> String {
    let folds = v.cross_validation.iter().flat_map(|cv| &cv.folds);
    let mut names: Vec<&str> = Vec::new();
    for t in folds.clone().flat_map(|f| &f.terms) {
        if !names.contains(&t.term.as_str()) {
            names.push(&t.term);
        }
    }
    let mut out = String::new();
    for name in names {
        let mut rows = Vec::new();
        for (i, f) in folds.clone().enumerate() {
            for t in f.terms.iter().filter(|t| t.term == name) {
                rows.push((format!("fold {}, before", i + 1), t.before));
                rows.push((format!("fold {}, after", i + 1), t.after));
            }
        }
        let what = (folds.clone().flat_map(|f| &f.terms))
            .find(|t| t.term == name)
            .map_or("", |t| t.what.as_str());
        let title = format!("\nHeld-out {what} (mm)\n");
        out += &errors_table(rows.into_iter(), &title, "count");
    }
    out
}

/// A table of error distributions `rows` (name, figures) under `title`,
/// the count column headed `count`; empty without rows.
fn errors_table(
    rows: impl Iterator<Item = (String, crate::calibrate::validate::PositionErrors)>,
    title: &str,
    count: &str,
) -> String {
    let mut t = String::new();
    for (name, p) in rows {
        if t.is_empty() {
            t += title;
            t += &format!(
                "  {:<28} {:>8} {:>8} {:>8} {:>8} {:>8}\n",
                "data", count, "mean", "RMS", "p95", "max"
            );
        }
        t += &format!(
            "  {:<28} {:>8} {:>8.4} {:>8.4} {:>8.4} {:>8.4}\n",
            name, p.count, p.mean, p.rms, p.p95, p.max
        );
    }
    t
}

/// What the method did, before the final LM's line.
fn method_lines(s: &crate::calibrate::SolverSummary) -> String {
    let mut t = String::new();
    if let Some(a) = &s.anneal {
        let o = &a.options;
        t += &format!(
            "Annealing: T0 {} mm, alpha {}, L {}, T_min {} mm, epsilon {} mm, ranges {} mm / {} deg \
             (twists) / {} deg (zeros); {} temperatures, {} energy evaluations; energy {:.4} -> \
             {:.4} mm; stopped: {}\n",
            o.t0,
            o.cooling,
            o.chain,
            o.t_min,
            o.target,
            o.step_mm,
            o.twist_step_deg,
            o.zero_step_deg,
            a.temperatures.len(),
            a.evaluations,
            a.start_energy,
            a.best_energy,
            a.stop.describe()
        );
        if let (Some(rule), Some(last)) = (&a.switch_rule, a.temperatures.last()) {
            t += &format!(
                "Switch (s0 {}, epsilon1 {}): at T = {:.3e} mm, energy {:.4} mm, after {} \
                 evaluations\n",
                rule.window, rule.epsilon, last.temperature, last.best, a.evaluations
            );
        }
    }
    if let Some(g) = &s.global {
        let searched = if g.circles.is_empty() {
            "no zero offset is free, so the start arm's LM is the search".to_string()
        } else {
            let n = g.minima.len();
            let twins = match g.twin_restarts {
                0 => String::new(),
                r => format!(", {r} restart(s) from a mirror image's zeros"),
            };
            format!(
                "{n} {} (the start arm, {} grid cell(s), {} random start(s){twins}) on the circles \
                 of {}",
                if n == 1 { "minimum" } else { "minima" },
                g.grid_starts,
                g.random_starts,
                g.circles.join(", ")
            )
        };
        t += &format!(
            "Global: {searched}; lowest cost reached {} time(s){}; stopped: {}{}\n",
            g.best_hits,
            match g.noise_level_hits {
                0 => String::new(),
                k => format!(
                    " ({k} of them at the noise level: a cost within cost/dof of the lowest and \
                     an arm within its uncertainty)"
                ),
            },
            g.stop.describe(),
            if g.sign_changes.is_empty() {
                String::new()
            } else {
                format!(
                    "; signs put in the nominal convention: {}",
                    g.sign_changes.join(", ")
                )
            }
        );
    }
    let phases: Vec<String> = s
        .phases
        .iter()
        .map(|p| {
            format!(
                "{} ({} cost, {} Jacobian)",
                p.name, p.cost_evaluations, p.jacobian_evaluations
            )
        })
        .collect();
    t += &format!("Phases: {}\n", phases.join("; "));
    t
}

/// The summary's line on a robust fit: its settings and the touches it
/// downweighted, by `file:line`.
fn robust_line(r: &crate::calibrate::RobustFit, noun: &str) -> String {
    use crate::calibrate::robust::DOWNWEIGHTED;
    let low = r.downweighted();
    let head = format!(
        "Robust: {} (k = {}), {} refit(s){}, scale {:.4}",
        r.loss.name(),
        r.scale_k,
        r.passes,
        if r.converged {
            ""
        } else {
            " (weights not settled)"
        },
        r.scale
    );
    if low.is_empty() {
        return format!("{head}; no {noun} weighed below {DOWNWEIGHTED}\n");
    }
    let shown: Vec<String> = low
        .iter()
        .take(20)
        .map(|t| format!("{} (point {}, weight {:.3})", t.at, t.point, t.weight))
        .collect();
    format!(
        "{head}; {} {} weighed below {DOWNWEIGHTED}: {}{}\n",
        low.len(),
        plural(noun),
        shown.join(", "),
        if low.len() > shown.len() { ", …" } else { "" }
    )
}

/// The summary's prior table: per free parameter with a tolerance, how much
/// of its information came from the data.
fn prior_table(p: &crate::calibrate::PriorReport) -> String {
    let mut t = String::from(
        "Prior (data share = 1 - posterior variance / prior variance; shift = correction in \
         tolerances):\n",
    );
    t += &format!(
        "  {:<8} {:<4} {:>10} {:>12} {:>10} {:>8}\n",
        "name", "unit", "tolerance", "post. sigma", "data share", "shift"
    );
    for e in &p.parameters {
        t += &format!(
            "  {:<8} {:<4} {:>10.6} {:>12.6} {:>9.1} % {:>+8.2}\n",
            e.name,
            e.unit,
            e.tolerance,
            e.posterior_sigma,
            100.0 * e.data_share,
            e.shift
        );
    }
    t
}

/// The verdict, and the notes that come with it (the same as the JSON's
/// `/verdict`): a χ² outside its range that is not a refusal is said here,
/// not only in the file.
fn verdict_line(v: &Verdict) -> String {
    let words = v.words(Spelling::Cli);
    let mut t = if v.usable {
        "Verdict: usable\n".to_string()
    } else {
        format!("Verdict: NOT usable — {}\n", words.reasons.join("; "))
    };
    for n in &words.notes {
        t += &format!("  note: {n}\n");
    }
    t + "\n"
}
