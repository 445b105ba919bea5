//! The tests computed: see the module's documentation.

use nalgebra::{Matrix3, Vector3, Vector4};

use super::{
    Acceptance, AcceptanceError, E_UNI, L_DIA, L_DIA_GROUPS, LDiaPlacement, LDiaRadius, P_FORM,
    P_SIZE, P_TEST_POINTS, Placement, SPAT, Settings, SpatPoint, SpherePoints, TestKind,
    TestResult, Use, enclosing_ball, fit_sphere_ls,
};
use crate::domain::ReferenceLength;
use crate::error::{InputError, OptionError, quoted};
use crate::metrics::Evaluation;
use crate::setting::Setting;

/// The acceptance tests of `points` (with the reference lengths `lengths`
/// of their file, and the cones' evaluation `cones` for the SPAT) under
/// `settings`: see the module's documentation.
///
/// # Errors
///
/// A sphere diameter out of range (in metres), an uncertainty that is not
/// a number ≥ 0, a probing placement with fewer than 25 points, an
/// articulated placement without exactly 5 articulations, a length naming
/// no placement, and a placement whose points fix no sphere: each by file,
/// line and field.
pub fn verify(
    settings: &Settings,
    points: SpherePoints<'_>,
    lengths: Option<(&[ReferenceLength], &str)>,
    cones: Option<&Evaluation>,
) -> Result<Acceptance, AcceptanceError> {
    check_settings(settings)?;
    let lengths = lengths.unwrap_or((&[], ""));
    let uses = uses(points, lengths)?;
    let mut placements = Vec::with_capacity(uses.len());
    for (s, &used_for) in uses.iter().enumerate() {
        placements.push(placement(settings, points, s, used_for)?);
    }
    let mut tests = worst_probing(&placements);
    let mut l_dia = Vec::new();
    for (s, _) in uses
        .iter()
        .enumerate()
        .filter(|(_, u)| **u == Use::Articulated)
    {
        let (test, placement) = articulated(settings, points, s)?;
        tests.push(test);
        l_dia.push(placement);
    }
    tests.extend(
        lengths
            .0
            .iter()
            .map(|l| e_uni(settings, &placements, l, lengths.1)),
    );
    let spat = cones.map(spat_points).unwrap_or_default();
    if let Some(worst) = spat
        .iter()
        .max_by(|a, b| a.delta_max.total_cmp(&b.delta_max))
    {
        let at = format!("cone {}", quoted(&worst.label));
        tests.push(TestResult::new(
            TestKind::Spat,
            SPAT,
            at,
            worst.delta_max,
            0.0,
            &settings.mpe,
        ));
    }
    let untested = (settings.mpe.limits.iter())
        .map(|(t, _)| *t)
        .filter(|t| !tests.iter().any(|r| r.test == *t))
        .collect();
    Ok(Acceptance {
        sphere_file: points.file.to_string(),
        sphere_diameter: settings.sphere_diameter,
        sphere_uncertainty: settings.sphere_uncertainty,
        ball_diameter: settings.ball_diameter,
        l_dia_radius: settings.l_dia_radius,
        mpe: settings.mpe.clone(),
        tests,
        untested,
        placements,
        l_dia,
        spat,
        prediction: None,
    })
}

/// The diameters and the uncertainty checked.
fn check_settings(s: &Settings) -> Result<(), OptionError> {
    crate::residuals::spheres::check_sphere_diameter(s.sphere_diameter)?;
    if !(s.ball_diameter.is_finite() && s.ball_diameter >= 0.0) {
        let why = "the probe ball's diameter is a number of mm ≥ 0";
        return Err(OptionError::new(
            Setting::BallDiameter,
            s.ball_diameter,
            why,
        ));
    }
    if !(s.sphere_uncertainty.is_finite() && s.sphere_uncertainty >= 0.0) {
        let why = "the sphere's standard uncertainty is a number of mm ≥ 0";
        return Err(OptionError::new(
            Setting::SphereUncertainty,
            s.sphere_uncertainty,
            why,
        ));
    }
    Ok(())
}

/// The articulations of placement `s`'s rows, ascending, distinct.
fn groups(points: SpherePoints<'_>, s: usize) -> Vec<u32> {
    let mut g: Vec<u32> = (points.rows.rows_of(s).iter())
        .filter_map(|&i| points.rows.articulation(i))
        .collect();
    g.sort_unstable();
    g.dedup();
    g
}

/// What each placement is used for, refusing what cannot be tested: a
/// length naming no placement, an articulated placement of other than 5
/// articulations, a probing placement of fewer than 25 points.
fn uses(
    points: SpherePoints<'_>,
    (lengths, file): (&[ReferenceLength], &str),
) -> Result<Vec<Use>, InputError> {
    let names = points.rows.spheres();
    for l in lengths {
        for (field, name) in [("point_a", &l.a), ("point_b", &l.b)] {
            if !names.contains(name) {
                let message = format!(
                    "{} is no sphere placement of {} (a length for E_Uni joins two placements' \
                     centres)",
                    quoted(name),
                    points.file
                );
                return Err(InputError::field(file, l.line, field, message));
            }
        }
    }
    let rows = points.rows;
    (0..names.len())
        .map(|s| {
            let of = rows.rows_of(s);
            let first = rows.line(of[0]);
            let g = groups(points, s);
            if g.len() > 1 {
                if g.len() != L_DIA_GROUPS {
                    let message = format!(
                        "sphere {} has {} articulations ({}): {L_DIA} needs exactly \
                         {L_DIA_GROUPS}, five points each in one articulation",
                        quoted(&names[s]),
                        g.len(),
                        g.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
                    );
                    return Err(InputError::field(
                        points.file,
                        first,
                        "articulation",
                        message,
                    ));
                }
                return Ok(Use::Articulated);
            }
            if lengths.iter().any(|l| l.a == names[s] || l.b == names[s]) {
                return Ok(Use::Length);
            }
            if of.len() < P_TEST_POINTS {
                let message = format!(
                    "sphere {} has {} points: {P_SIZE} and {P_FORM} need {P_TEST_POINTS} (ISO \
                     10360-5's pattern); a placement for E_Uni is named by a length, one for \
                     {L_DIA} has an articulation column",
                    quoted(&names[s]),
                    of.len()
                );
                return Err(InputError::field(points.file, first, "sphere", message));
            }
            Ok(Use::Probing)
        })
        .collect()
}

/// The points of rows `rows`.
fn at(points: SpherePoints<'_>, rows: &[usize]) -> Vec<[f64; 3]> {
    rows.iter().map(|&i| points.centres[i]).collect()
}

/// A fit failure as an input error at the placement's first line.
fn unfit(points: SpherePoints<'_>, s: usize, what: &str, e: super::FitError) -> InputError {
    let rows = points.rows.rows_of(s);
    let name = &points.rows.spheres()[s];
    InputError::field(
        points.file,
        points.rows.line(rows[0]),
        "sphere",
        format!("sphere {}{what}: {e}", quoted(name)),
    )
}

/// Placement `s`'s free least-squares sphere, and its `P_Size` and
/// `P_Form` if a probing placement.
fn placement(
    settings: &Settings,
    points: SpherePoints<'_>,
    s: usize,
    used_for: Use,
) -> Result<Placement, InputError> {
    let rows = points.rows.rows_of(s);
    let fit = fit_sphere_ls(&at(points, &rows), None).map_err(|e| unfit(points, s, "", e))?;
    let diameter = 2.0 * (fit.radius - settings.ball_diameter / 2.0);
    let name = points.rows.spheres()[s].clone();
    let mut tests = Vec::new();
    if used_for == Use::Probing {
        let u_d = settings.sphere_uncertainty;
        let size = diameter - settings.sphere_diameter;
        let u_size = 2.0 * u_d.hypot(fit.diameter_sigma());
        tests.push(TestResult::new(
            TestKind::PSize,
            P_SIZE,
            name.clone(),
            size,
            u_size,
            &settings.mpe,
        ));
        let u_form = 2.0 * u_d.hypot(form_sigma(&fit, &at(points, &rows)));
        let form = fit.form();
        tests.push(TestResult::new(
            TestKind::PForm,
            P_FORM,
            name.clone(),
            form,
            u_form,
            &settings.mpe,
        ));
    }
    Ok(Placement {
        name,
        line: points.rows.line(rows[0]),
        used_for,
        points: rows.len(),
        fit,
        diameter,
        tests,
    })
}

/// σ of the range of the radial residuals from the fit's own covariance:
/// `σ̂ sqrt(gᵀ (JᵀJ)⁻¹ g)`, `g = J_max − J_min` (the radius's part
/// cancels).
fn form_sigma(fit: &super::SphereFit, p: &[[f64; 3]]) -> f64 {
    let Some(sigma) = fit.sigma else {
        return 0.0;
    };
    let r = &fit.residuals;
    let (lo, hi) = (0..r.len()).fold((0, 0), |(lo, hi), i| {
        (
            if r[i] < r[lo] { i } else { lo },
            if r[i] > r[hi] { i } else { hi },
        )
    });
    let row = |i: usize| {
        let v = Vector3::from(p[i]) - Vector3::from(fit.centre);
        let u = v / v.norm();
        Vector4::new(-u[0], -u[1], -u[2], -1.0)
    };
    let g = row(hi) - row(lo);
    let n_inv = fit.covariance(1.0);
    (g.transpose() * n_inv * g)[(0, 0)].max(0.0).sqrt() * sigma
}

/// The worst `P_Size` and the worst `P_Form` over the probing placements.
fn worst_probing(placements: &[Placement]) -> Vec<TestResult> {
    [TestKind::PSize, TestKind::PForm]
        .iter()
        .filter_map(|&kind| {
            (placements.iter())
                .flat_map(|p| p.tests.iter())
                .filter(|t| t.test == kind)
                .max_by(|a, b| {
                    let (da, va) = a.badness();
                    let (db, vb) = b.badness();
                    da.cmp(&db).then(va.total_cmp(&vb))
                })
                .cloned()
        })
        .collect()
}

/// Per articulation, its number and fit; the points' summed squared
/// residuals and degrees of freedom.
type GroupFits = (Vec<(u32, super::SphereFit)>, f64, usize);

/// Each articulation's centre of placement `s` (radius held at `held` or
/// fitted), and the points' summed squared residuals and degrees of
/// freedom.
fn group_centres(
    points: SpherePoints<'_>,
    s: usize,
    held: Option<f64>,
) -> Result<GroupFits, InputError> {
    let rows = points.rows.rows_of(s);
    let (mut fits, mut ss, mut dof) = (Vec::new(), 0.0, 0);
    for g in groups(points, s) {
        let of: Vec<usize> = (rows.iter().copied())
            .filter(|&i| points.rows.articulation(i) == Some(g))
            .collect();
        let what = format!(", articulation {g}");
        let fit = fit_sphere_ls(&at(points, &of), held).map_err(|e| unfit(points, s, &what, e))?;
        ss += fit.residuals.iter().map(|r| r * r).sum::<f64>();
        dof += of.len() - if held.is_some() { 3 } else { 4 };
        fits.push((g, fit));
    }
    Ok((fits, ss, dof))
}

/// The diameter of the smallest sphere enclosing `centres`.
fn enclosed(centres: &[[f64; 3]]) -> f64 {
    2.0 * enclosing_ball(centres).radius
}

/// Step of the numerical derivatives of `L_Dia`, mm: far above the fits'
/// convergence (1e-13 relative), far below any noise.
const STEP_MM: f64 = 1e-5;

/// Placement `s`'s `L_Dia` and its centres.
fn articulated(
    settings: &Settings,
    points: SpherePoints<'_>,
    s: usize,
) -> Result<(TestResult, LDiaPlacement), InputError> {
    let probe_radius = (settings.sphere_diameter + settings.ball_diameter) / 2.0;
    let held = (settings.l_dia_radius == LDiaRadius::Held).then_some(probe_radius);
    let (fits, ss, dof) = group_centres(points, s, held)?;
    let centres: Vec<[f64; 3]> = fits.iter().map(|(_, f)| f.centre).collect();
    let value = enclosed(&centres);
    let sigma = if dof > 0 {
        (ss / dof as f64).sqrt()
    } else {
        0.0
    };
    // ∇ᵀ C ∇ over the centres, each C_g = σ̂² (JᵀJ)⁻¹ of its fit.
    let mut var = 0.0;
    for (g, (_, fit)) in fits.iter().enumerate() {
        let grad = Vector3::from_fn(|k, _| {
            let mut moved = centres.clone();
            moved[g][k] += STEP_MM;
            let up = enclosed(&moved);
            moved[g][k] -= 2.0 * STEP_MM;
            (up - enclosed(&moved)) / (2.0 * STEP_MM)
        });
        let c = Matrix3::from_fn(|i, j| fit.normal_inverse[i][j]) * (sigma * sigma);
        var += (grad.transpose() * c * grad)[(0, 0)];
    }
    if let Some(r) = held {
        // ∂L/∂D: the centres refitted with the held diameter moved.
        let (up, _, _) = group_centres(points, s, Some(r + STEP_MM / 2.0))?;
        let (down, _, _) = group_centres(points, s, Some(r - STEP_MM / 2.0))?;
        let l = |f: &[(u32, super::SphereFit)]| {
            enclosed(&f.iter().map(|(_, f)| f.centre).collect::<Vec<_>>())
        };
        let d = (l(&up) - l(&down)) / STEP_MM;
        var += (d * settings.sphere_uncertainty).powi(2);
    }
    let name = points.rows.spheres()[s].clone();
    let ball = enclosing_ball(&centres);
    let test = TestResult::new(
        TestKind::LDia,
        L_DIA,
        name.clone(),
        value,
        2.0 * var.max(0.0).sqrt(),
        &settings.mpe,
    );
    let placement = LDiaPlacement {
        name,
        centres: fits.iter().map(|(g, f)| (*g, f.centre)).collect(),
        enclosing_centre: ball.centre,
        sigma,
    };
    Ok((test, placement))
}

/// The `E_Uni` of length `l`: between its placements' centres.
fn e_uni(
    settings: &Settings,
    placements: &[Placement],
    l: &ReferenceLength,
    file: &str,
) -> TestResult {
    let find = |name: &str| {
        placements
            .iter()
            .find(|p| p.name == name)
            .expect("checked by uses")
    };
    let (a, b) = (find(&l.a), find(&l.b));
    let d = Vector3::from(a.fit.centre) - Vector3::from(b.fit.centre);
    let measured = d.norm();
    let n = d / measured;
    let cov = |p: &Placement| {
        let s = p.fit.sigma.unwrap_or(0.0);
        Matrix3::from_fn(|i, j| p.fit.normal_inverse[i][j]) * (s * s)
    };
    let noise = (n.transpose() * (cov(a) + cov(b)) * n)[(0, 0)].max(0.0);
    let u = 2.0 * (l.uncertainty.unwrap_or(0.0).powi(2) + noise).sqrt();
    let at = format!("{}–{} ({file}:{})", l.a, l.b, l.line);
    let mut t = TestResult::new(
        TestKind::EUni,
        E_UNI,
        at,
        measured - l.distance,
        u,
        &super::Mpe::default(),
    );
    t.length = Some(l.distance);
    t.decided(&settings.mpe, l.distance)
}

/// The SPAT's cones.
fn spat_points(ev: &Evaluation) -> Vec<SpatPoint> {
    (ev.points.iter())
        .map(|p| SpatPoint {
            label: p.label.clone(),
            touches: p.touches,
            delta_max: p.delta_max,
            two_s: p.two_s,
            half_range: p.half_range,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::acceptance::{Decision, parse_mpe};
    use crate::domain::Spheres;

    /// Probe centres on a sphere of radius 15.7 (a 25.4 mm sphere, a 6 mm
    /// ball) about `c`, `n` of them.
    fn cap(c: [f64; 3], r: f64, n: usize, wobble: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                let (a, b) = (i as f64 * 2.39996, 0.2 + 1.3 * i as f64 / n as f64);
                let rr = r + wobble * ((i * 7 % 5) as f64 - 2.0);
                [
                    c[0] + rr * b.sin() * a.cos(),
                    c[1] + rr * b.sin() * a.sin(),
                    c[2] + rr * b.cos(),
                ]
            })
            .collect()
    }

    fn settings(mpe: &str) -> Settings {
        Settings {
            sphere_diameter: 25.4,
            sphere_uncertainty: 0.0005,
            ball_diameter: 6.0,
            l_dia_radius: LDiaRadius::Held,
            mpe: if mpe.is_empty() {
                Default::default()
            } else {
                parse_mpe(mpe).unwrap()
            },
        }
    }

    #[test]
    fn figures_decisions_and_refusals() {
        let mut rows = Spheres::new(1, 0);
        let mut xyz = Vec::new();
        let placed = [
            ("A", [0.0, 0.0, 0.0], 25),
            ("B", [300.0, 0.0, 0.0], 8),
            ("C", [0.0, 0.0, 0.0], 8),
        ];
        for (name, c, n) in placed {
            for p in cap(c, 15.7 + 0.002, n, 0.001) {
                rows.push(name, &[0.0], 2 + xyz.len(), None);
                xyz.push(p);
            }
        }
        let lengths =
            crate::io::parse_lengths("point_a,point_b,distance\nB,C,299.99\n", "l.csv").unwrap();
        let points = SpherePoints {
            rows: &rows,
            file: "s.csv",
            centres: &xyz,
        };
        let s = settings("P_Size=0.1,P_Form=0.1,E_Uni=0.001+L/1000000,L_Dia=0.01");
        let a = verify(&s, points, Some((&lengths, "l.csv")), None).unwrap();
        let size = &a.tests[0];
        assert_eq!((size.figure.as_str(), size.at.as_str()), (P_SIZE, "A"));
        let fit = &a.placements[0].fit;
        assert_eq!(size.value, 2.0 * (fit.radius - 3.0) - 25.4);
        assert!((size.value - 0.004).abs() < 0.002, "{size:?}");
        assert_eq!(size.decision, Some(Decision::Pass));
        let e = a.tests.iter().find(|t| t.test == TestKind::EUni).unwrap();
        assert!(
            (e.value - 0.01).abs() < 1e-9 && e.length == Some(299.99),
            "{e:?}"
        );
        assert_eq!(e.decision, Some(Decision::Fail));
        assert_eq!(a.untested, vec![TestKind::LDia]);
        assert_eq!(a.placements[1].used_for, Use::Length);
        assert_eq!(a.placements[0].tests.len(), 2);
        assert_eq!(a.not_passed().len(), 2, "{:?}", a.not_passed());
        // B without its length: too few points for P_Size.
        let e = verify(&s, points, None, None).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("s.csv:27: field `sphere`: sphere `B` has 8 points"),
            "{e}"
        );
        assert!(e.to_string().contains("need 25"), "{e}");
        // A length naming no placement.
        let bad = crate::io::parse_lengths("point_a,point_b,distance\nA,D,1\n", "l.csv").unwrap();
        let e = verify(&s, points, Some((&bad, "l.csv")), None).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("l.csv:2: field `point_b`: `D` is no sphere"),
            "{e}"
        );
        // A diameter in metres.
        let mut m = settings("");
        m.sphere_diameter = 0.0254;
        let e = verify(&m, points, Some((&lengths, "l.csv")), None).unwrap_err();
        assert!(e.to_string().contains("metres"), "{e}");
    }

    #[test]
    fn l_dia_groups_are_five() {
        let mut rows = Spheres::new(1, 0);
        let mut xyz = Vec::new();
        // Five articulations each a patch of five, their centres apart.
        for g in 0..5u32 {
            let c = [0.001 * g as f64, -0.002 * (g % 2) as f64, 0.0];
            for p in cap(c, 15.7, 25, 0.0)
                .into_iter()
                .skip(5 * g as usize)
                .take(5)
            {
                rows.push("L", &[0.0], 2 + xyz.len(), Some(g + 1));
                xyz.push(p);
            }
        }
        let points = SpherePoints {
            rows: &rows,
            file: "s.csv",
            centres: &xyz,
        };
        let a = verify(&settings("L_Dia=0.05"), points, None, None).unwrap();
        let t = &a.tests[0];
        assert_eq!(t.figure, L_DIA);
        let centres: Vec<[f64; 3]> = a.l_dia[0].centres.iter().map(|c| c.1).collect();
        assert!((t.value - 2.0 * enclosing_ball(&centres).radius).abs() < 1e-15);
        // The centres are recovered (points exact), the figure their spread.
        let truth: Vec<[f64; 3]> = (0..5)
            .map(|g| [0.001 * g as f64, -0.002 * (g % 2) as f64, 0.0])
            .collect();
        for (c, t) in centres.iter().zip(&truth) {
            assert!(crate::geometry::distance(c, t) < 1e-9, "{c:?} {t:?}");
        }
        assert!(
            (t.value - 2.0 * enclosing_ball(&truth).radius).abs() < 1e-9,
            "{t:?}"
        );
        assert_eq!(t.decision, Some(Decision::Pass));
        // Four articulations: refused at the placement's first line.
        let sub: Vec<usize> = (0..20).collect();
        let four = rows.subset(&sub);
        let points = SpherePoints {
            rows: &four,
            file: "s.csv",
            centres: &xyz[..20],
        };
        let e = verify(&settings(""), points, None, None).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("s.csv:2: field `articulation`: sphere `L` has 4 articulations"),
            "{e}"
        );
    }
}
