//! Reading an arm file's schema: the checks serde cannot express (joint
//! kinds and models, limits, the probe's ball, tools, the physics beyond
//! geometry), then the arm in mm and rad with its unit warnings.

use super::*;

impl ArmFile {
    /// The arm (mm, rad) and the warnings, after the checks serde cannot
    /// express; `text` and `file` locate the messages.
    pub(crate) fn to_arm(&self, text: &str, file: &str) -> Result<(Arm, Vec<Warning>), InputError> {
        let joints = self.joint.get_ref();
        // Per-joint keys first, as serde's missing-key errors came before
        // the joint count when `d` was required by the schema.
        let models = joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let model = j.get_ref().model(j.span(), i, text, file)?;
                Ok((model, j.get_ref().kind(i, text, file)?))
            })
            .collect::<Result<Vec<(JointModel, JointKind)>, InputError>>()?;
        if !supports_joints(joints.len()) {
            // Blame the first joint too many, or the last.
            let blamed = joints.get(MAX_JOINTS).or(joints.last());
            let line = line_of(text, blamed.map_or(self.joint.span(), |j| j.span()).start);
            return Err(InputError::field(
                file,
                line,
                "joint",
                unsupported(joints.len()),
            ));
        }
        let numbers = self.numbers();
        if let Some((ctx, field, v)) = numbers.iter().find(|(_, _, v)| !v.get_ref().is_finite()) {
            let line = line_of(text, v.span().start);
            let raw = text.get(v.span()).unwrap_or("?");
            let message = format!("{ctx}{} is not a finite number", quoted(raw));
            return Err(InputError::field(file, line, *field, message));
        }

        let (lu, au) = (self.length_unit, self.angle_unit);
        let mut arm = Arm {
            name: self.name.clone(),
            params: DhParams {
                joints: Vec::with_capacity(joints.len()),
                probe: [&self.probe.x, &self.probe.y, &self.probe.z]
                    .map(|v| lu.to_internal(*v.get_ref())),
            },
            limits: Vec::with_capacity(joints.len()),
            prior: None,
            physics: Box::default(),
            ball_diameter_mm: self.ball_diameter(text, file)?,
            tools: self.tools(text, file)?,
        };
        for (i, (j, &(model, kind))) in joints.iter().map(Spanned::get_ref).zip(&models).enumerate()
        {
            arm.params.joints.push(j.joint(model, kind, lu, au));
            let limits = j.limits(i, kind, (lu, au), text, file)?;
            arm.limits.push(limits);
        }
        arm.physics = Box::new(self.physics(text, file)?);
        Ok((arm, self.unit_warnings(text, file)))
    }

    /// The `[[tool]]` tables, checked: a name not empty, not the default
    /// tool's, not repeated; an offset of three numbers (finite: checked
    /// with every number first).
    fn tools(&self, text: &str, file: &str) -> Result<Vec<crate::domain::Tool>, InputError> {
        let mut seen: Vec<&str> = Vec::new();
        let mut out = Vec::with_capacity(self.tool.len());
        for t in self.tool.iter().map(Spanned::get_ref) {
            let name = t.name.get_ref();
            if let Some(why) = crate::io::tools::name_refused(name, &seen) {
                let line = line_of(text, t.name.span().start);
                return Err(InputError::field(file, line, "name", why));
            }
            seen.push(name);
            let offset = match t.offset_mm.get_ref()[..] {
                [ref x, ref y, ref z] => [x, y, z].map(|c| *c.get_ref()),
                ref other => {
                    return Err(InputError::field(
                        file,
                        line_of(text, t.offset_mm.span().start),
                        "offset_mm",
                        format!(
                            "[[tool]] {}: expected [x, y, z] (mm), found {} values",
                            quoted(name),
                            other.len()
                        ),
                    ));
                }
            };
            let ctx = format!("[[tool]] {}", quoted(name));
            let ball = (t.ball_diameter_mm.as_ref())
                .map(|d| checked_ball(d, &ctx, text, file))
                .transpose()?;
            out.push(crate::domain::Tool {
                name: name.clone(),
                offset,
                ball_diameter_mm: ball,
            });
        }
        Ok(out)
    }

    /// `[probe] ball_diameter_mm`, checked: in mm, between
    /// [`MIN_BALL_DIAMETER_MM`] (below it, metres) and
    /// [`MAX_BALL_DIAMETER_MM`]. (Finite: checked with every number first.)
    fn ball_diameter(&self, text: &str, file: &str) -> Result<Option<f64>, InputError> {
        (self.probe.ball_diameter_mm.as_ref())
            .map(|d| checked_ball(d, "[probe]", text, file))
            .transpose()
    }

    /// The masses, gravity and corrections the file states, checked.
    fn physics(&self, text: &str, file: &str) -> Result<Physics, InputError> {
        let at = |span: Range<usize>, field: &str, message: String| {
            InputError::field(file, line_of(text, span.start), field, message)
        };
        let triple = |v: &Spanned<Vec<Spanned<f64>>>, field: &str, ctx: &str| match v.get_ref()[..]
        {
            [ref x, ref y, ref z] => Ok([x, y, z].map(|c| *c.get_ref())),
            ref other => Err(at(
                v.span(),
                field,
                format!("{ctx}expected [x, y, z], found {} values", other.len()),
            )),
        };
        let mass = |kg: &Option<Spanned<f64>>,
                    com: &Option<Spanned<Vec<Spanned<f64>>>>,
                    ctx: &str|
         -> Result<Option<Mass>, InputError> {
            let com_mm = com.as_ref().map(|c| triple(c, "com_mm", ctx)).transpose()?;
            match kg {
                None if com_mm.is_some() => Err(at(
                    com.as_ref().map_or(0..0, Spanned::span),
                    "com_mm",
                    format!("{ctx}a centre of mass without `mass_kg`"),
                )),
                None => Ok(None),
                Some(m) if *m.get_ref() < 0.0 => Err(at(
                    m.span(),
                    "mass_kg",
                    format!("{ctx}a mass is not negative, got {}", m.get_ref()),
                )),
                Some(m) => Ok(Some(Mass {
                    kg: *m.get_ref(),
                    com_mm,
                })),
            }
        };
        let au = self.angle_unit;
        let mut physics = Physics::default();
        for (i, (ctx, j)) in self.joints_in_context().enumerate() {
            physics.link_masses.push(mass(&j.mass_kg, &j.com_mm, &ctx)?);
            physics
                .compliance
                .push(j.compliance_rad_per_nm.as_ref().map(|c| *c.get_ref()));
            for h in j.harmonics.iter().flat_map(|h| h.get_ref()) {
                let order = match h.get_ref()[..] {
                    [ref k, _, _] => *k.get_ref(),
                    _ => f64::NAN,
                };
                if !(order.fract() == 0.0 && (1.0..=f64::from(MAX_HARMONIC_ORDER)).contains(&order))
                {
                    return Err(at(
                        h.span(),
                        "harmonics",
                        format!(
                            "{ctx}expected [order, sin, cos] with a whole order from 1 to {MAX_HARMONIC_ORDER} and amplitudes in {au}"
                        ),
                    ));
                }
                let v = h.get_ref();
                physics.harmonics.push(Harmonic {
                    joint: i,
                    order: order as u32,
                    sin: au.to_internal(*v[1].get_ref()),
                    cos: au.to_internal(*v[2].get_ref()),
                });
            }
        }
        if physics.link_masses.iter().all(Option::is_none) {
            physics.link_masses.clear();
        }
        if physics.compliance.iter().all(Option::is_none) {
            physics.compliance.clear();
        }
        physics.probe_mass = mass(&self.probe.mass_kg, &self.probe.com_mm, "[probe]: ")?;
        self.read_backlash(&mut physics, &at)?;
        if let Some(g) = &self.gravity {
            let v = triple(g, "gravity", "")?;
            if v.iter().all(|c| *c == 0.0) {
                return Err(at(g.span(), "gravity", "a direction, not zero".into()));
            }
            physics.gravity = Some(v);
        }
        physics.cte_per_k = self.cte_per_k.as_ref().map(|c| *c.get_ref());
        physics.reference_temperature_c =
            (self.reference_temperature_c.as_ref()).map(|c| *c.get_ref());
        Ok(physics)
    }

    /// Each joint's `backlash` (angle_unit; length_unit for a slide) into
    /// `physics`, after its masses: a play needs a mass to press one of its
    /// flanks ([`crate::corrections`]). A negative value (not physical: the
    /// link against its load) is read as written, since a calibrated arm
    /// file carries what its fit found.
    fn read_backlash(
        &self,
        physics: &mut Physics,
        at: &impl Fn(Range<usize>, &'static str, String) -> InputError,
    ) -> Result<(), InputError> {
        let joints = self.joint.get_ref().iter().map(Spanned::get_ref);
        for (i, j) in joints.enumerate() {
            let Some(b) = &j.backlash else {
                physics.backlash.push(None);
                continue;
            };
            if !physics.has_masses() {
                return Err(at(
                    b.span(),
                    "backlash",
                    format!(
                        "joint {}: a backlash needs masses: their gravity torque decides which \
                         flank the joint rests on; state `mass_kg` of the links and of the tool \
                         ([probe])",
                        i + 1
                    ),
                ));
            }
            let slides = j.kind.as_ref().is_some_and(|k| k.get_ref() == "prismatic");
            let unit = JointUnit {
                kind: if slides {
                    JointKind::Prismatic
                } else {
                    JointKind::Revolute
                },
                lu: self.length_unit,
                au: self.angle_unit,
            };
            physics.backlash.push(Some(unit.to_internal(*b.get_ref())));
        }
        if physics.backlash.iter().all(Option::is_none) {
            physics.backlash.clear();
        }
        Ok(())
    }

    /// The joints, base to probe, each with the context its messages start
    /// with (`joint 3: `).
    fn joints_in_context(&self) -> impl Iterator<Item = (String, &JointFile)> {
        let joints = self.joint.get_ref().iter().map(Spanned::get_ref);
        (joints.enumerate()).map(|(i, j)| (format!("joint {}: ", i + 1), j))
    }

    /// Every number of the file, base to probe, with its context and key.
    fn numbers(&self) -> Vec<(String, &'static str, &Spanned<f64>)> {
        let mut out = Vec::new();
        for (ctx, j) in self.joints_in_context() {
            for (field, v) in [("theta", &j.theta), ("alpha", &j.alpha), ("a", &j.a)] {
                out.push((ctx.clone(), field, v));
            }
            if let Some(d) = &j.d {
                out.push((ctx.clone(), "d", d));
            }
            if let Some(b) = &j.hbeta {
                out.push((ctx.clone(), "hbeta", b));
            }
            for v in j.limits.iter().flat_map(|l| l.get_ref()) {
                out.push((ctx.clone(), "limits", v));
            }
            if let Some(m) = &j.mass_kg {
                out.push((ctx.clone(), "mass_kg", m));
            }
            if let Some(c) = &j.compliance_rad_per_nm {
                out.push((ctx.clone(), "compliance_rad_per_nm", c));
            }
            if let Some(b) = &j.backlash {
                out.push((ctx.clone(), "backlash", b));
            }
            for v in j.com_mm.iter().flat_map(|c| c.get_ref()) {
                out.push((ctx.clone(), "com_mm", v));
            }
            for v in (j.harmonics.iter().flat_map(|h| h.get_ref())).flat_map(|h| h.get_ref()) {
                out.push((ctx.clone(), "harmonics", v));
            }
        }
        for (field, v) in [
            ("cte_per_k", &self.cte_per_k),
            ("reference_temperature_c", &self.reference_temperature_c),
            ("mass_kg", &self.probe.mass_kg),
            ("ball_diameter_mm", &self.probe.ball_diameter_mm),
        ] {
            if let Some(v) = v {
                out.push((String::new(), field, v));
            }
        }
        for v in self.gravity.iter().flat_map(|g| g.get_ref()) {
            out.push((String::new(), "gravity", v));
        }
        for v in self.probe.com_mm.iter().flat_map(|g| g.get_ref()) {
            out.push(("[probe]: ".to_string(), "com_mm", v));
        }
        let p = &self.probe;
        for (field, v) in [("x", &p.x), ("y", &p.y), ("z", &p.z)] {
            out.push(("[probe]: ".to_string(), field, v));
        }
        for t in self.tool.iter().map(Spanned::get_ref) {
            let ctx = format!("[[tool]] {}: ", quoted(t.name.get_ref()));
            for v in t.offset_mm.get_ref() {
                out.push((ctx.clone(), "offset_mm", v));
            }
            if let Some(v) = &t.ball_diameter_mm {
                out.push((ctx.clone(), "ball_diameter_mm", v));
            }
        }
        out
    }

    /// Warnings where the stated unit looks wrong: a length over
    /// [`PLAUSIBLE_METRES`] in metres, a twist or zero offset over a full
    /// turn in radians.
    fn unit_warnings(&self, text: &str, file: &str) -> Vec<Warning> {
        let numbers = self.numbers();
        let first = |fields: &[&str], limit: f64| {
            numbers
                .iter()
                .find(|(_, f, v)| fields.contains(f) && v.get_ref().abs() > limit)
        };
        let long = (self.length_unit == LengthUnit::M)
            .then(|| first(&["a", "d", "x", "y", "z"], PLAUSIBLE_METRES))
            .flatten()
            .map(|(_, field, v)| {
                let message = format!(
                    "lengths declared in metres (length_unit = \"m\"), but |{}| m is longer \
                     than any arm ({PLAUSIBLE_METRES} m): these lengths look like millimetres; \
                     write length_unit = \"mm\" if so",
                    v.get_ref()
                );
                (field, v, message)
            });
        let turn = (self.angle_unit == AngleUnit::Rad)
            .then(|| first(&["theta", "alpha", "hbeta"], std::f64::consts::TAU))
            .flatten()
            .map(|(_, field, v)| {
                let message = format!(
                    "angles declared in radians (angle_unit = \"rad\"), but |{}| is more than \
                     a full turn (2π): these angles look like degrees; write angle_unit = \"deg\" \
                     if so",
                    v.get_ref()
                );
                (field, v, message)
            });
        (long.into_iter().chain(turn))
            .map(|(field, v, message)| Warning {
                file: file.to_string(),
                line: Some(line_of(text, v.span().start)),
                field: Some(field.to_string()),
                message,
            })
            .collect()
    }
}
