//! A set of poses as the chain sees them under the corrections, and the
//! corrections' Jacobian columns.

use super::gravity::Loads;
use super::{Beyond, Column, Physics};
use crate::kernel::{Batch, FreeRows, LANES, LaneOp, run_lanes};
use crate::kernel::{Post, PreparedPoses};
use crate::params::{DhParams, JointKind};
use std::sync::Arc;

/// What was recorded with each pose beyond its readings.
#[derive(Clone, Copy, Debug, Default)]
pub struct Conditions<'a> {
    /// Per pose, the temperature, °C.
    pub temperature_c: Option<&'a [f64]>,
    /// Per pose, the time, s (from any origin).
    pub time_s: Option<&'a [f64]>,
    /// Per pose and joint (pose-major), the direction the joint approached
    /// its reading from: `+1`, `−1`, `0` not known
    /// ([`crate::io::approach`]). A known direction decides the flank a
    /// backlash rests on in place of the gravity torque's sign.
    pub approach: Option<&'a [i8]>,
}

/// A correction column's derivative, per pose a factor times …
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// … the chain's column `c` (a joint's zero offset: a reading's change).
    Joint(usize),
    /// … the position before the expansion.
    Expansion,
    /// … a unit vector along a base axis.
    Axis(usize),
}

impl Kind {
    /// Row `r` of this correction's column at factor `f`: `v` is the
    /// chain column's entry in that row (read by a joint's correction
    /// only), `pos` the position before the expansion, `offset` the
    /// drift's origin. [`Effects::extend`], [`Effects::extend_pose`] and
    /// [`Effects::finish_free`] all form their entries here, so they agree
    /// to the bit.
    #[inline(always)]
    fn entry(self, r: usize, f: f64, v: f64, pos: &[f64; 3], offset: &[f64; 3]) -> f64 {
        match self {
            Kind::Joint(_) => f * v,
            Kind::Expansion if r < 3 => f * (pos[r] - offset[r]),
            Kind::Axis(a) if r == a => f,
            Kind::Expansion | Kind::Axis(_) => 0.0,
        }
    }
}

/// Poses under the corrections: the readings the chain sees (with the
/// expansion and drift after it, `Post`) and, per pose, the factors of
/// the fitted corrections' Jacobian columns.
#[derive(Clone, Debug)]
pub struct Effects {
    /// The corrected poses.
    pub poses: PreparedPoses,
    kinds: Vec<Kind>,
    /// `factors[i·m + k]`: column `k`'s factor at pose `i`.
    factors: Vec<f64>,
}

/// Why the corrections cannot be applied to a set of poses.
pub(crate) type EffectsError = String;

/// A pose set's conditions as the corrections need them: per pose the
/// temperature from the reference (K) and the time from the first (h).
struct Elapsed {
    kelvin: Vec<f64>,
    hours: Vec<f64>,
    /// Whether an expansion or a drift acts (fitted or stated): the
    /// position then moves after the chain.
    moves: bool,
}

impl Elapsed {
    /// Refuses an expansion (fitted or stated) without temperatures and a
    /// drift without times.
    fn of(
        physics: &Physics,
        fit: &Beyond,
        len: usize,
        c: Conditions<'_>,
    ) -> Result<Elapsed, EffectsError> {
        let thermal = fit.thermal || physics.cte_per_k.is_some_and(|c| c != 0.0);
        let drift = fit.drift || physics.drift_mm_per_h.is_some();
        if thermal && c.temperature_c.is_none() {
            return Err("thermal expansion needs a `temperature` column (°C)".into());
        }
        if drift && c.time_s.is_none() {
            return Err("drift needs a `time` column (s)".into());
        }
        let reference = physics.reference_c();
        let kelvin = match c.temperature_c {
            Some(t) if thermal => t.iter().map(|t| t - reference).collect(),
            _ => vec![0.0; len],
        };
        let hours = match c.time_s {
            Some(t) if drift => {
                let t0 = t.iter().copied().fold(f64::INFINITY, f64::min);
                t.iter().map(|t| (t - t0) / 3600.0).collect()
            }
            _ => vec![0.0; len],
        };
        Ok(Elapsed {
            kelvin,
            hours,
            moves: thermal || drift,
        })
    }
}

impl Effects {
    /// The poses `raw` (the readings' own cos and sin) recorded under
    /// `conditions`, corrected by `physics` (the effective values: stated
    /// or at the fit's point), with the Jacobian factors of the models
    /// `fit` estimates. No transcendental call per pose: the harmonics
    /// `sin(kq)`, `cos(kq)` by the angle-sum recurrence from the reading's
    /// own, the corrected angles through the angle sum with the small
    /// correction.
    ///
    /// A prismatic joint's readings (mm) pass through unchanged but for
    /// its backlash (mm, along the gravity force on the slide): its encoder
    /// harmonics and compliance are refused (both models are of a revolute
    /// joint's angle), the expansion and drift act after the chain as for
    /// any joint.
    ///
    /// # Errors
    ///
    /// An expansion without temperatures, a drift without times; encoder
    /// harmonics or a compliance of a prismatic joint, a fitted backlash of
    /// a Hayati slide (no geometry column moves it).
    pub fn new(
        arm: &DhParams,
        physics: &Physics,
        fit: &Beyond,
        raw: &PreparedPoses,
        conditions: Conditions<'_>,
    ) -> Result<Effects, EffectsError> {
        Effects::new_cached(arm, physics, fit, raw, conditions, None)
    }

    /// [`Effects::new`], the corrected readings taken from `cache` (that
    /// of the poses `raw` recorded under `conditions`, and of no others)
    /// when they were corrected for the same arm and physics before.
    pub(crate) fn new_cached(
        arm: &DhParams,
        physics: &Physics,
        fit: &Beyond,
        raw: &PreparedPoses,
        conditions: Conditions<'_>,
        cache: Option<&SeenCache>,
    ) -> Result<Effects, EffectsError> {
        let (n, len) = (arm.joints.len(), raw.len());
        check_prismatic(arm, physics, fit)?;
        let elapsed = Elapsed::of(physics, fit, len, conditions)?;
        let trig: Vec<(&[f64], &[f64])> = (0..n).map(|j| raw.column_trig(j)).collect();
        let loads = physics.needs_loads(fit) || physics.compliance.iter().any(|c| c.is_some());
        let make = || Seen::new(arm, physics, loads, raw, &trig, conditions.approach);
        // Kept only with the gravity torques, what costs: the rest costs
        // about what the key and a copy of the readings do (and a fit
        // rarely asks twice for the same corrections without them:
        // callgrind, `beyond/harmonics-100`, 3 hits in 16 asks a fit).
        let kept = (cache.filter(|_| loads)).map(|c| c.get(seen_key(arm, physics, raw), make));
        let fresh_tau;
        let (tau, cos, sin) = match &kept {
            Some(seen) => (&seen.tau[..], seen.cos.clone(), seen.sin.clone()),
            None => {
                let Seen { tau, cos, sin } = make();
                fresh_tau = tau;
                (&fresh_tau[..], cos, sin)
            }
        };
        let flanks = Flanks {
            tau,
            approach: conditions.approach,
            joints: n,
        };
        let mut poses = PreparedPoses::from_trig(n, raw.prismatic_mask(), len, cos, sin);
        let (cte, drift) = (
            physics.cte_per_k.unwrap_or(0.0),
            physics.drift_mm_per_h.unwrap_or([0.0; 3]),
        );
        // Only where something acts after the chain: a fit of harmonics or
        // compliance alone asks for its corrections at every trial point.
        let post = elapsed.moves.then(|| Post {
            scale: elapsed.kelvin.iter().map(|k| 1.0 + cte * k).collect(),
            offset: elapsed.hours.iter().map(|h| drift.map(|v| v * h)).collect(),
        });
        // The expansion's column (fitted: it moves) divides by the scale.
        let scale = post.as_ref().map_or(&[][..], |p| &p.scale[..]);
        let factors = factors(fit, &trig, &flanks, &elapsed, scale, len);
        if let Some(post) = post {
            poses = poses.with_post(post);
        }
        Ok(Effects {
            poses,
            kinds: kinds(fit, arm),
            factors,
        })
    }

    /// Pose `i`'s Jacobian into `out`: the chain's columns `jac` (at the
    /// corrected pose, position `pos`), then the corrections' — the layout's
    /// order when the correction block is its first.
    #[inline(always)]
    pub(crate) fn extend(
        &self,
        i: usize,
        pos: &[f64; 3],
        jac: &[[f64; 3]],
        out: &mut Vec<[f64; 3]>,
    ) {
        self.extend_rows(i, pos, jac, out);
    }

    /// [`Effects::extend`] of a tool pose's `6 × (4n+3)` Jacobian (position
    /// rows, then rotation rows): a joint's correction turns the tool as
    /// the joint does; an expansion and a drift move its position only.
    #[inline(always)]
    pub(crate) fn extend_pose(
        &self,
        i: usize,
        pos: &[f64; 3],
        jac: &[[f64; 6]],
        out: &mut Vec<[f64; 6]>,
    ) {
        self.extend_rows(i, pos, jac, out);
    }

    /// How the columns `free` of [`Effects::extend`]'s layout (the chain's
    /// `params` columns, then the corrections') come out of the kernel's
    /// [`ArmKernel::for_each_free_jacobian`](crate::kernel::ArmKernel):
    /// the chain's columns to ask it for, one per free column (a joint's
    /// correction asks for the joint's column, which it scales; the others
    /// for any, which they replace), and the corrections to finish in
    /// place per pose ([`Effects::finish_free`]).
    pub(crate) fn free_plan(&self, free: &[usize], params: usize) -> FreePlan {
        let mut chain = Vec::with_capacity(free.len());
        let mut fixes = Vec::new();
        for (a, &c) in free.iter().enumerate() {
            match c.checked_sub(params) {
                None => chain.push(c),
                Some(k) => {
                    chain.push(match self.kinds[k] {
                        Kind::Joint(c) => c,
                        Kind::Expansion | Kind::Axis(_) => 0,
                    });
                    fixes.push((a, k));
                }
            }
        }
        FreePlan { chain, fixes }
    }

    /// Pose `i`'s free columns (`rows`, as the kernel hands them over for
    /// `plan.chain`, at position `pos`) finished: each correction's column
    /// as [`Effects::extend`] forms it, the same operations on the same
    /// values.
    #[inline(always)]
    pub(crate) fn finish_free(
        &self,
        plan: &FreePlan,
        i: usize,
        pos: &[f64; 3],
        mut rows: FreeRows<'_>,
    ) {
        let m = self.kinds.len();
        let factors = &self.factors[i * m..(i + 1) * m];
        let offset = self.drift_offset(i);
        for &(a, k) in &plan.fixes {
            let (g, u) = (a / LANES, a % LANES);
            let f = factors[k];
            for (r, row) in rows.iter_mut().enumerate() {
                let v: &mut f64 = &mut row[g][u];
                *v = self.kinds[k].entry(r, f, *v, pos, &offset);
            }
        }
    }

    /// Pose `i`'s drift offset (zero where nothing moves after the chain),
    /// the origin of its expansion column.
    #[inline(always)]
    fn drift_offset(&self, i: usize) -> [f64; 3] {
        self.poses.post().map_or([0.0; 3], |p| p.offset[i])
    }

    /// [`Effects::extend`] of a Jacobian of `N` rows, the position's first.
    #[inline(always)]
    fn extend_rows<const N: usize>(
        &self,
        i: usize,
        pos: &[f64; 3],
        jac: &[[f64; N]],
        out: &mut Vec<[f64; N]>,
    ) {
        out.clear();
        out.extend_from_slice(jac);
        let m = self.kinds.len();
        let offset = self.drift_offset(i);
        for (kind, &f) in self.kinds.iter().zip(&self.factors[i * m..(i + 1) * m]) {
            let chain = match *kind {
                Kind::Joint(c) => jac[c],
                Kind::Expansion | Kind::Axis(_) => [0.0; N],
            };
            out.push(std::array::from_fn(|r| {
                kind.entry(r, f, chain[r], pos, &offset)
            }));
        }
    }
}

/// [`Effects::free_plan`]: per free column, the chain's column the kernel
/// hands over in its place, and the corrections among them (their free
/// index, their column among the corrections').
#[derive(Clone, Debug)]
pub(crate) struct FreePlan {
    pub(crate) chain: Vec<usize>,
    fixes: Vec<(usize, usize)>,
}

/// What the corrections of one set of poses depend on beyond the fit's
/// columns: per pose and joint the gravity torque, and the readings' cos
/// and sin corrected (by the harmonics, compliance and backlash).
#[derive(Debug)]
pub(crate) struct Seen {
    /// Per pose and joint (pose-major), the gravity torque (empty when no
    /// correction needs the loads).
    tau: Vec<f64>,
    cos: Vec<Vec<f64>>,
    sin: Vec<Vec<f64>>,
}

impl Seen {
    /// The poses `raw` (their columns of cos and sin `trig`, the joints'
    /// approach `approach`) under `physics`, with the gravity torques when
    /// `loads`.
    fn new(
        arm: &DhParams,
        physics: &Physics,
        loads: bool,
        raw: &PreparedPoses,
        trig: &[(&[f64], &[f64])],
        approach: Option<&[i8]>,
    ) -> Seen {
        let (n, len) = (trig.len(), raw.len());
        let loads = loads.then(|| Loads::new(arm, physics));
        let mut tau = vec![0.0; if loads.is_some() { len * n } else { 0 }];
        if let Some(loads) = &loads {
            gravity_torques(loads, trig, &mut tau);
        }
        let flanks = Flanks {
            tau: &tau,
            approach,
            joints: n,
        };
        let delta = reading_corrections(physics, trig, &flanks, len);
        let (cos, sin) = corrected_trig(trig, &delta, len, raw.prismatic_mask());
        Seen { tau, cos, sin }
    }
}

/// The bits of everything [`Seen::new`] with the loads reads besides the
/// poses and their conditions: the arm's chain and probe, the masses and
/// gravity, each joint's compliance and backlash, the harmonics in order.
/// (Only corrections with the loads are kept.)
fn seen_key(arm: &DhParams, physics: &Physics, raw: &PreparedPoses) -> Vec<u64> {
    let n = arm.joints.len();
    let mut key = Vec::with_capacity(16 * n + 32);
    key.extend([raw.len() as u64, n as u64]);
    for j in &arm.joints {
        key.extend([j.a, j.d, j.alpha, j.theta, j.beta].map(f64::to_bits));
        key.extend([j.model as u64, j.kind as u64]);
    }
    key.extend(arm.probe.map(f64::to_bits));
    key.push(physics.link_masses.len() as u64);
    let mut mass = |m: &Option<super::Mass>| match m {
        None => key.push(0),
        Some(m) => {
            let com = m.com_mm;
            key.extend([1, u64::from(com.is_some()), m.kg.to_bits()]);
            key.extend(com.unwrap_or_default().map(f64::to_bits));
        }
    };
    physics.link_masses.iter().for_each(&mut mass);
    mass(&physics.probe_mass);
    key.extend(super::gravity::gravity_vector(physics).map(f64::to_bits));
    for j in 0..n {
        key.extend([physics.compliance_of(j), physics.backlash_of(j)].map(f64::to_bits));
    }
    key.push(physics.harmonics.len() as u64);
    for h in &physics.harmonics {
        key.extend([h.joint as u64, u64::from(h.order)]);
        key.extend([h.sin, h.cos].map(f64::to_bits));
    }
    key
}

/// The corrected readings of one set of poses for the last few arms and
/// physics they were corrected at, most recent last: a fit asks for them
/// again and again at the same point (LM's cost at a trial point and its
/// normal equations there once accepted; every pass of the assessment at
/// the solution), and they are what costs in [`Effects::new`]. A value
/// taken from here is the one computed afresh, to the bit. Up to
/// [`SEEN_ENTRIES`] entries, of at most [`SEEN_MAX_POSES`] poses (a larger
/// set is corrected afresh each time, not held twice in memory).
#[derive(Debug, Default)]
pub(crate) struct SeenCache(std::sync::Mutex<Vec<(Vec<u64>, Arc<Seen>)>>);

/// [`SeenCache`]'s entries: a touch term asks for one arm per tool.
const SEEN_ENTRIES: usize = 4;

/// [`SeenCache`]'s largest set of poses: its entries then hold at most
/// 4 × 6 MB (7 joints' cos, sin and torque at 8 B each).
const SEEN_MAX_POSES: usize = 1 << 15;

impl Clone for SeenCache {
    fn clone(&self) -> SeenCache {
        SeenCache(std::sync::Mutex::new(self.entries().clone()))
    }
}

impl SeenCache {
    /// The entries (a panic elsewhere while they were held left them whole:
    /// each is replaced whole).
    fn entries(&self) -> std::sync::MutexGuard<'_, Vec<(Vec<u64>, Arc<Seen>)>> {
        self.0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The entry of `key`, made by `make` (and kept) when there is none.
    /// An entry taken becomes the most recent; the least recent goes
    /// when a new one comes to a full cache.
    fn get(&self, key: Vec<u64>, make: impl FnOnce() -> Seen) -> Arc<Seen> {
        if let Some(seen) = self.take(&key) {
            return seen;
        }
        // Made without the lock: another thread may make the same entry
        // meanwhile (the same values), and only one is kept.
        let seen = Arc::new(make());
        if seen.cos.first().is_some_and(|c| c.len() <= SEEN_MAX_POSES) && self.take(&key).is_none()
        {
            let mut entries = self.entries();
            if entries.len() == SEEN_ENTRIES {
                entries.remove(0);
            }
            entries.push((key, Arc::clone(&seen)));
        }
        seen
    }

    /// The entry of `key`, made the most recent.
    fn take(&self, key: &[u64]) -> Option<Arc<Seen>> {
        let mut entries = self.entries();
        let at = entries.iter().position(|(k, _)| k == key)?;
        let entry = entries.remove(at);
        let seen = Arc::clone(&entry.1);
        entries.push(entry);
        Some(seen)
    }
}

/// Whether joint `j` (0-based) of `arm` slides.
fn slides(arm: &DhParams, j: usize) -> bool {
    (arm.joints.get(j)).is_some_and(|x| x.kind == JointKind::Prismatic)
}

/// Refuses the reading corrections of a prismatic joint: encoder
/// harmonics and compliance are models of a revolute joint's angle (a
/// slide's reading is a length, and its load a force along it).
fn check_prismatic(arm: &DhParams, physics: &Physics, fit: &Beyond) -> Result<(), EffectsError> {
    let slides = |j: usize| slides(arm, j);
    let harmonic = (physics.harmonics.iter().map(|h| h.joint))
        .chain(fit.harmonics.iter().map(|h| h.0))
        .find(|&j| slides(j));
    if let Some(j) = harmonic {
        return Err(format!(
            "joint {} is prismatic: encoder harmonics are a model of a revolute joint's angle",
            j + 1
        ));
    }
    let hayati_slide = fit
        .backlash
        .iter()
        .copied()
        .find(|&j| slides(j) && arm.joints[j].model == crate::params::JointModel::Hayati);
    if let Some(j) = hayati_slide {
        return Err(format!(
            "joint {} is a Hayati slide: its reading moves no geometry parameter, so its backlash \
             has no column to fit (state it in the arm file instead)",
            j + 1
        ));
    }
    let compliant = (0..arm.joints.len())
        .filter(|&j| physics.compliance_of(j) != 0.0)
        .chain(fit.compliance.iter().copied())
        .find(|&j| slides(j));
    if let Some(j) = compliant {
        return Err(format!(
            "joint {} is prismatic: the compliance model turns a revolute joint under its gravity \
             torque",
            j + 1
        ));
    }
    Ok(())
}

/// The encoder readings whose corrected joint angles ([`Effects`]:
/// harmonics and compliance, not the expansion or drift) are `angles`:
/// what a true arm with these errors reads in the pose `angles`. Fixed
/// point `q ← angles − c(q)`: the corrections are micro-radians, their
/// change with `q` smaller still, so a few rounds reach round-off. A
/// prismatic joint's reading (mm) is its own: nothing corrects it (see
/// [`Effects::new`]).
pub fn readings_for(arm: &DhParams, physics: &Physics, angles: &[f64]) -> Vec<f64> {
    let loads = loads_of(arm, physics);
    let mut q = angles.to_vec();
    for _ in 0..8 {
        let delta = pose_corrections(arm, physics, loads.as_ref(), &q);
        for (j, d) in delta.iter().enumerate() {
            q[j] = angles[j] - d;
        }
    }
    q
}

/// The joint angles the chain sees at the encoder readings `readings`
/// (harmonics and compliance, as [`Effects`] corrects a pose): the inverse
/// of [`readings_for`], to round-off.
pub fn angles_for(arm: &DhParams, physics: &Physics, readings: &[f64]) -> Vec<f64> {
    let delta = pose_corrections(arm, physics, loads_of(arm, physics).as_ref(), readings);
    readings.iter().zip(&delta).map(|(q, d)| q + d).collect()
}

/// The gravity loads, when some joint states a compliance or a backlash.
fn loads_of(arm: &DhParams, physics: &Physics) -> Option<Loads> {
    (physics.needs_loads(&Beyond::default())).then(|| Loads::new(arm, physics))
}

/// Per joint, the reading correction of the one pose `q` (the same
/// corrections the fit applies, [`reading_corrections`]). A prismatic
/// joint's column holds its reading (mm) in place of the cosine, as the
/// kernel's prepared poses do, and its correction is zero (nothing
/// corrects a slide's reading, see [`Effects::new`]).
fn pose_corrections(
    arm: &DhParams,
    physics: &Physics,
    loads: Option<&Loads>,
    q: &[f64],
) -> Vec<f64> {
    let n = q.len();
    let slides = |j: usize| slides(arm, j);
    let (cos, sin): (Vec<f64>, Vec<f64>) = (q.iter().enumerate())
        .map(|(j, v)| {
            if slides(j) {
                (*v, 0.0)
            } else {
                (v.cos(), v.sin())
            }
        })
        .unzip();
    let trig: Vec<(&[f64], &[f64])> = (0..n)
        .map(|j| (std::slice::from_ref(&cos[j]), std::slice::from_ref(&sin[j])))
        .collect();
    let mut tau = vec![0.0; if loads.is_some() { n } else { 0 }];
    if let Some(loads) = loads {
        loads.torques(|j| cos[j], |j| sin[j], &mut tau);
    }
    let flanks = Flanks {
        tau: &tau,
        approach: None,
        joints: n,
    };
    let delta = reading_corrections(physics, &trig, &flanks, 1);
    // A slide's correction is its backlash alone (its other models are
    // refused), a length added to its reading.
    (0..n)
        .map(|j| match delta.get(j).and_then(|d| d.first()) {
            Some(d) if !slides(j) || physics.backlash_of(j) != 0.0 => *d,
            _ => 0.0,
        })
        .collect()
}

/// `(cos kq, sin kq)` from `cos q`, `sin q` by the angle-sum recurrence.
#[inline]
fn multiple(c: f64, s: f64, k: u32) -> (f64, f64) {
    let (mut ck, mut sk) = (c, s);
    for _ in 1..k {
        (ck, sk) = (ck * c - sk * s, sk * c + ck * s);
    }
    (ck, sk)
}

/// `(cos d, sin d)` of a correction `d`: its Taylor series while `|d| <
/// 0.01` rad (the next term below 10⁻²³), else the library's.
#[inline]
fn small_sin_cos(d: f64) -> (f64, f64) {
    if d.abs() >= 0.01 {
        let (s, c) = d.sin_cos();
        return (c, s);
    }
    let d2 = d * d;
    let c = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
    let s = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)));
    (c, s)
}

/// Per joint, its reading correction at every pose (empty for a joint
/// without one): the harmonics of its reading, compliance × torque and the
/// backlash on the flank the approach or the torque decides
/// ([`Flanks::side`]).
fn reading_corrections(
    physics: &Physics,
    trig: &[(&[f64], &[f64])],
    flanks: &Flanks<'_>,
    len: usize,
) -> Vec<Vec<f64>> {
    let tau = flanks.tau;
    let n = trig.len();
    let mut delta: Vec<Vec<f64>> = vec![Vec::new(); n];
    for h in &physics.harmonics {
        let (c, s) = trig[h.joint];
        let d = &mut delta[h.joint];
        d.resize(len, 0.0);
        for i in 0..len {
            let (ck, sk) = multiple(c[i], s[i], h.order);
            d[i] += h.sin * sk + h.cos * ck;
        }
    }
    if !tau.is_empty() || flanks.approach.is_some() {
        for (j, d) in delta.iter_mut().enumerate() {
            let kappa = physics.compliance_of(j);
            if kappa != 0.0 && !tau.is_empty() {
                d.resize(len, 0.0);
                for i in 0..len {
                    d[i] += kappa * tau[i * n + j];
                }
            }
            let b = physics.backlash_of(j);
            if b != 0.0 {
                d.resize(len, 0.0);
                for (i, d) in d.iter_mut().enumerate() {
                    *d += b * flanks.side(i, j);
                }
            }
        }
    }
    delta
}

/// What decides the flank each joint rests on at each pose: the direction
/// it approached the reading from where known, else its gravity torque.
struct Flanks<'a> {
    /// Per pose and joint (pose-major), the gravity torque (empty: none).
    tau: &'a [f64],
    /// Per pose and joint (pose-major), the direction of approach.
    approach: Option<&'a [i8]>,
    joints: usize,
}

impl Flanks<'_> {
    /// The flank of joint `j` at pose `i`: `+1`, `−1` or `0` (floating).
    #[inline]
    fn side(&self, i: usize, j: usize) -> f64 {
        let k = i * self.joints + j;
        match self.approach.map_or(0, |a| a[k]) {
            0 => flank(self.tau.get(k).copied().unwrap_or(0.0)),
            s => f64::from(s.signum()),
        }
    }
}

/// Which gear flank a joint under the gravity torque (or force) `tau`
/// rests on: `+1` along the torque, `−1` against, `0` for none (a joint
/// that gravity does not load floats within its play: no correction).
#[inline]
fn flank(tau: f64) -> f64 {
    if tau > 0.0 {
        1.0
    } else if tau < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// The corrected angles' cos and sin, joint by joint, through the angle sum;
/// a joint without a correction keeps its own, a slide (bit `j` of
/// `prismatic`) adds its correction (mm) to its reading.
#[allow(clippy::type_complexity)] // cos and sin columns, as PreparedPoses holds them
fn corrected_trig(
    trig: &[(&[f64], &[f64])],
    delta: &[Vec<f64>],
    len: usize,
    prismatic: u16,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let (mut cos, mut sin) = (
        Vec::with_capacity(trig.len()),
        Vec::with_capacity(trig.len()),
    );
    for (j, (&(c, s), d)) in trig.iter().zip(delta).enumerate() {
        if d.is_empty() {
            cos.push(c.to_vec());
            sin.push(s.to_vec());
            continue;
        }
        if prismatic & (1 << j) != 0 {
            cos.push(c.iter().zip(d).map(|(q, d)| q + d).collect());
            sin.push(s.to_vec());
            continue;
        }
        let (mut cj, mut sj) = (vec![0.0; len], vec![0.0; len]);
        for i in 0..len {
            let (cd, sd) = small_sin_cos(d[i]);
            cj[i] = c[i] * cd - s[i] * sd;
            sj[i] = s[i] * cd + c[i] * sd;
        }
        cos.push(cj);
        sin.push(sj);
    }
    (cos, sin)
}

/// The fitted columns' kinds, in the block's order: a reading correction
/// moves the probe as the joint's zero offset θ does (a slide's backlash as
/// its offset `d`).
fn kinds(fit: &Beyond, arm: &DhParams) -> Vec<Kind> {
    let n = arm.joints.len();
    (fit.columns().into_iter())
        .map(|column| match column {
            Column::Backlash(j)
                if arm
                    .joints
                    .get(j)
                    .is_some_and(|x| x.kind == JointKind::Prismatic) =>
            {
                Kind::Joint(n + j)
            }
            Column::Compliance(j) | Column::Sin(j, _) | Column::Cos(j, _) | Column::Backlash(j) => {
                Kind::Joint(3 * n + j)
            }
            Column::Expansion => Kind::Expansion,
            Column::Drift(a) => Kind::Axis(a),
        })
        .collect()
}

/// Per pose (pose-major, `len` poses), the factor of each fitted column
/// ([`kinds`]); `scale`, the expansion's per pose, is read only by its
/// column.
fn factors(
    fit: &Beyond,
    trig: &[(&[f64], &[f64])],
    flanks: &Flanks<'_>,
    elapsed: &Elapsed,
    scale: &[f64],
    len: usize,
) -> Vec<f64> {
    let (tau, n) = (flanks.tau, flanks.joints);
    let columns = fit.columns();
    let m = columns.len();
    let mut factors = vec![0.0; len * m];
    if m == 0 {
        return factors;
    }
    for (i, f) in factors.chunks_exact_mut(m).enumerate() {
        for (fk, column) in f.iter_mut().zip(&columns) {
            *fk = match *column {
                Column::Compliance(j) => tau[i * n + j] * 1e-6,
                Column::Backlash(j) => flanks.side(i, j),
                Column::Sin(j, k) => multiple(trig[j].0[i], trig[j].1[i], k).1,
                Column::Cos(j, k) => multiple(trig[j].0[i], trig[j].1[i], k).0,
                Column::Expansion => elapsed.kelvin[i] * 1e-6 / scale[i],
                Column::Drift(_) => elapsed.hours[i],
            };
        }
    }
    factors
}

/// Per pose and joint (pose-major, into `tau`), the gravity torque of
/// `loads` at the poses whose columns of cos and sin are `trig`: four poses
/// at a time side by side, on the widest lanes the CPU has ([`run_lanes`]:
/// the same bits as one pose at a time).
fn gravity_torques(loads: &Loads, trig: &[(&[f64], &[f64])], tau: &mut [f64]) {
    if !trig.is_empty() {
        run_lanes(Torques { loads, trig, tau });
    }
}

/// [`gravity_torques`]' loop, on [`Batch`] lanes: an AVX register per
/// value where the portable lanes' arrays were loaded and stored around
/// each operation (callgrind, `beyond/compliance-100`: the corrections of
/// 100 poses 80.6 → 73.6 k instructions; the torques are still about 8 %
/// of that fit, most of the rest the chain's frames kept in memory).
struct Torques<'a> {
    loads: &'a Loads,
    trig: &'a [(&'a [f64], &'a [f64])],
    tau: &'a mut [f64],
}

impl LaneOp for Torques<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Batch>(self) {
        let Torques { loads, trig, tau } = self;
        let n = trig.len();
        // A prismatic joint's column holds its readings and no sin.
        let at = |column: &[f64], i: usize| {
            (column.get(i..).and_then(|v| v.first_chunk::<LANES>())).map_or(L::from(0.0), L::load)
        };
        let mut four = vec![L::from(0.0); n];
        let (mut frames, mut one) = (Vec::new(), Vec::new());
        let first = (tau.len() / n) / LANES * LANES;
        let mut groups = tau.chunks_exact_mut(LANES * n);
        for (g, t) in (&mut groups).enumerate() {
            let i = LANES * g;
            loads.torques_with(
                |j| at(trig[j].0, i),
                |j| at(trig[j].1, i),
                &mut four,
                &mut frames,
            );
            for (j, v) in four.iter().enumerate() {
                for (l, x) in v.to_array().into_iter().enumerate() {
                    t[l * n + j] = x;
                }
            }
        }
        let sin = |j: usize, i: usize| trig[j].1.get(i).copied().unwrap_or(0.0);
        for (k, t) in groups.into_remainder().chunks_exact_mut(n).enumerate() {
            let i = first + k;
            loads.torques_with(|j| trig[j].0[i], |j| sin(j, i), t, &mut one);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::Harmonic;
    use crate::kernel::ArmKernel;
    use crate::params::ChainShape;

    /// A 6-joint arm whose second joint slides.
    fn sliding() -> DhParams {
        let mut arm = DhParams::paper_nominal();
        arm.joints[1] = arm.joints[1].with_kind(JointKind::Prismatic);
        arm
    }

    fn poses(arm: &DhParams) -> PreparedPoses {
        let q = [
            [0.1, 150.0, 0.3, -0.2, 0.5, 1.0],
            [0.4, -80.0, 0.1, 0.2, -0.5, 2.0],
        ];
        PreparedPoses::for_shape(arm.shape().unwrap(), &q).unwrap()
    }

    /// The torques four poses at a time are those of one pose at a time,
    /// to the bit: a chain with a slide and a Hayati joint, masses with and
    /// without a stated centre, a tool's, gravity off the axes; pose counts
    /// that leave 0 to 3 poses after the groups of four.
    #[test]
    fn torques_four_at_a_time_are_those_of_one() {
        use crate::corrections::Mass;
        let mut arm = sliding();
        arm.joints[2] = crate::params::DhJoint::hayati(310.0, 0.02, 0.1, 0.003);
        let physics = Physics {
            link_masses: vec![
                Some(Mass::at_middle(1.3)),
                Some(Mass {
                    kg: 2.1,
                    com_mm: Some([10.0, -40.0, 25.0]),
                }),
                None,
                Some(Mass::at_middle(0.7)),
                Some(Mass {
                    kg: 0.4,
                    com_mm: Some([0.0, 5.0, -3.0]),
                }),
                Some(Mass::at_middle(0.2)),
            ],
            probe_mass: Some(Mass {
                kg: 0.3,
                com_mm: Some([1.0, 2.0, 30.0]),
            }),
            gravity: Some([0.1, -0.3, -1.0]),
            ..Physics::default()
        };
        let loads = Loads::new(&arm, &physics);
        let mut rng = crate::random::rng(5, 0);
        for count in [1usize, 4, 6, 7, 9, 13] {
            let q: Vec<[f64; 6]> = (0..count)
                .map(|_| {
                    std::array::from_fn(|j| {
                        let v: f64 = rand::RngExt::random_range(&mut rng, -3.0..3.0);
                        if j == 1 { 100.0 * v } else { v }
                    })
                })
                .collect();
            let raw = PreparedPoses::for_shape(arm.shape().unwrap(), &q).unwrap();
            let n = arm.joints.len();
            let trig: Vec<(&[f64], &[f64])> = (0..n).map(|j| raw.column_trig(j)).collect();
            // The widest lanes this CPU has, and the portable ones.
            let mut four = vec![0.0; count * n];
            gravity_torques(&loads, &trig, &mut four);
            let mut portable = vec![0.0; count * n];
            Torques {
                loads: &loads,
                trig: &trig,
                tau: &mut portable,
            }
            .run::<crate::kernel::Lanes>();
            let sin = |j: usize, i: usize| trig[j].1.get(i).copied().unwrap_or(0.0);
            let mut one = vec![0.0; count * n];
            for (i, t) in one.chunks_exact_mut(n).enumerate() {
                loads.torques(|j| trig[j].0[i], |j| sin(j, i), t);
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&four), bits(&one), "{count} poses");
            assert_eq!(bits(&portable), bits(&one), "{count} poses, portable lanes");
            assert!(one.iter().all(|t| t.is_finite()) && one.iter().any(|&t| t != 0.0));
        }
    }

    /// An expansion scales what the chain makes of a prismatic joint's
    /// readings, which pass through unchanged (no angle sum touches them).
    #[test]
    fn a_slides_readings_pass_through_the_corrections() {
        let arm = sliding();
        let raw = poses(&arm);
        let physics = Physics {
            cte_per_k: Some(10e-6),
            ..Physics::default()
        };
        let t = [30.0, 30.0];
        let conditions = Conditions {
            temperature_c: Some(&t),
            ..Conditions::default()
        };
        let e = Effects::new(&arm, &physics, &Beyond::default(), &raw, conditions).unwrap();
        assert_eq!(e.poses.shape(), Some(arm.shape().unwrap()));
        assert_eq!(e.poses.column_trig(1), raw.column_trig(1));
        let k = ArmKernel::new(&arm).unwrap();
        let (mut seen, mut plain) = ([[0.0; 3]; 2], [[0.0; 3]; 2]);
        k.positions(&e.poses, 0..2, &mut seen).unwrap();
        k.positions(&raw, 0..2, &mut plain).unwrap();
        let scale = 1.0 + 10e-6 * (30.0 - physics.reference_c());
        for (s, p) in seen.iter().zip(&plain) {
            for r in 0..3 {
                assert!((s[r] - scale * p[r]).abs() < 1e-9);
            }
        }
    }

    /// Every bit of the poses as corrected and of the Jacobian factors.
    fn bits_of(e: &Effects) -> Vec<u64> {
        let mut out: Vec<u64> = e.factors.iter().map(|v| v.to_bits()).collect();
        for j in 0..e.poses.joints() {
            let (c, s) = e.poses.column_trig(j);
            out.extend(c.iter().chain(s).map(|v| v.to_bits()));
        }
        out
    }

    /// Corrections taken from the cache are those computed afresh, to the
    /// bit; a change of anything they depend on (a compliance, a mass, the
    /// arm's geometry, gravity) is computed afresh, not taken from the
    /// entry of another; the oldest entry goes when a fifth comes.
    #[test]
    fn corrections_kept_are_those_computed_afresh() {
        use crate::corrections::Mass;
        let arm = sliding();
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            // Across the base axis, so that every joint carries some.
            gravity: Some([0.3, -1.0, -0.2]),
            compliance: vec![None, None, Some(2e-5), Some(1e-5), None, None],
            backlash: vec![None, Some(0.05), None, None, Some(1e-4), None],
            harmonics: vec![Harmonic {
                joint: 2,
                order: 2,
                sin: 1e-4,
                cos: -2e-4,
            }],
            ..Physics::default()
        };
        let fit = Beyond {
            compliance: vec![2, 3],
            ..Beyond::default()
        };
        let raw = poses(&arm);
        let cache = SeenCache::default();
        let fresh = |arm: &DhParams, physics: &Physics, fit: &Beyond| {
            bits_of(&Effects::new(arm, physics, fit, &raw, Conditions::default()).unwrap())
        };
        let kept = |arm: &DhParams, physics: &Physics, fit: &Beyond| {
            let e =
                Effects::new_cached(arm, physics, fit, &raw, Conditions::default(), Some(&cache));
            bits_of(&e.unwrap())
        };
        let none = Beyond::default();
        let expected = fresh(&arm, &physics, &fit);
        assert_eq!(kept(&arm, &physics, &fit), expected, "kept");
        assert_eq!(cache.entries().len(), 1);
        // The same arm and physics, without the columns (a cost): a hit.
        assert_eq!(kept(&arm, &physics, &none), fresh(&arm, &physics, &none));
        assert_eq!(kept(&arm, &physics, &fit), expected, "taken");
        assert_eq!(cache.entries().len(), 1, "the same corrections");
        type Change = fn(&mut DhParams, &mut Physics);
        let changes: [(&str, Change); 15] = [
            ("compliance", |_, p| p.compliance[2] = Some(1e-5)),
            ("backlash", |_, p| p.backlash[4] = Some(2e-4)),
            ("harmonic sin", |_, p| p.harmonics[0].sin = 2e-4),
            ("harmonic order", |_, p| p.harmonics[0].order = 3),
            ("mass", |_, p| p.link_masses[3] = Some(Mass::at_middle(2.5))),
            ("centre", |_, p| {
                p.link_masses[3] = Some(Mass {
                    kg: 2.0,
                    com_mm: Some([0.0, 10.0, 0.0]),
                })
            }),
            ("probe mass", |_, p| {
                p.probe_mass = Some(Mass::at_middle(0.6))
            }),
            ("gravity", |_, p| p.gravity = Some([0.0, 0.1, -1.0])),
            ("a", |a, _| a.joints[2].a += 1e-9),
            ("d", |a, _| a.joints[3].d += 1e-9),
            ("alpha", |a, _| a.joints[0].alpha += 1e-9),
            ("theta", |a, _| a.joints[4].theta += 1e-9),
            ("beta", |a, _| {
                let j = &a.joints[2];
                a.joints[2] = crate::params::DhJoint::hayati(j.theta, j.a, j.alpha, 1e-3)
            }),
            ("probe", |a, _| a.probe[0] += 1e-6),
            ("a second harmonic", |_, p| {
                p.harmonics.push(Harmonic {
                    joint: 4,
                    order: 1,
                    sin: 1e-4,
                    cos: 0.0,
                })
            }),
        ];
        for (what, change) in changes {
            let (mut arm, mut physics) = (arm.clone(), physics.clone());
            change(&mut arm, &mut physics);
            let want = fresh(&arm, &physics, &fit);
            assert_ne!(want, expected, "{what}: changes the corrections");
            assert_eq!(kept(&arm, &physics, &fit), want, "{what}");
        }
        assert_eq!(cache.entries().len(), SEEN_ENTRIES);
        // The first entry went when the fifth came: computed afresh again.
        assert_eq!(kept(&arm, &physics, &fit), expected);
    }

    /// The cache keeps the entries taken most recently: one taken again
    /// stays when a new one comes to a full cache, the least recent goes.
    #[test]
    fn the_least_recently_taken_entry_goes() {
        let cache = SeenCache::default();
        let made = std::cell::Cell::new(0);
        let get = |k: u64| {
            cache.get(vec![k], || {
                made.set(made.get() + 1);
                Seen {
                    tau: vec![k as f64],
                    cos: vec![vec![0.0]],
                    sin: vec![vec![0.0]],
                }
            })
        };
        for k in 0..SEEN_ENTRIES as u64 {
            get(k);
        }
        assert_eq!(get(0).tau, [0.0]);
        assert_eq!(made.get(), SEEN_ENTRIES, "0 was kept");
        get(99);
        get(0);
        assert_eq!(made.get(), SEEN_ENTRIES + 1, "0 stayed");
        get(1);
        assert_eq!(made.get(), SEEN_ENTRIES + 2, "1 went");
    }

    /// A play of `b` on two joints: each reading is off by `b` along its
    /// gravity torque (`sgn τ`), a vertical axis (no torque) by nothing; a
    /// slide by `b` mm along the gravity force on it. The fitted column is
    /// the zero offset's (the slide's `d`'s) times `sgn τ`, and the
    /// simulator's inverse gives back the readings.
    #[test]
    fn a_backlash_follows_the_gravity_torque() {
        use crate::corrections::{Mass, gravity};
        let mut arm = sliding();
        // Turn the base axis across gravity, so that the slide carries some.
        let masses = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            gravity: Some([0.3, -1.0, -0.2]),
            ..Physics::default()
        };
        let play = 0.02f64.to_radians();
        let physics = Physics {
            backlash: vec![None, Some(0.05), Some(play), None, None, None],
            ..masses.clone()
        };
        let raw = poses(&arm);
        let fit = Beyond {
            backlash: vec![1, 2],
            ..Beyond::default()
        };
        let e = Effects::new(&arm, &physics, &fit, &raw, Conditions::default()).unwrap();
        let q = [
            [0.1, 150.0, 0.3, -0.2, 0.5, 1.0],
            [0.4, -80.0, 0.1, 0.2, -0.5, 2.0],
        ];
        for (i, q) in q.iter().enumerate() {
            let mut tau = [0.0; 6];
            gravity::torques(&arm, &physics, q, &mut tau);
            assert!(tau[1].abs() > 0.1 && tau[2].abs() > 0.1, "{tau:?}");
            let (c, s) = e.poses.column_trig(1);
            assert!((c[i] - (q[1] + 0.05 * tau[1].signum())).abs() < 1e-12);
            assert_eq!(s, raw.column_trig(1).1);
            let (c, s) = e.poses.column_trig(2);
            let turned = q[2] + play * tau[2].signum();
            assert!((c[i] - turned.cos()).abs() < 1e-15 && (s[i] - turned.sin()).abs() < 1e-15);
            assert_eq!(e.poses.column_trig(3), raw.column_trig(3));
            // The columns: the slide's d (column n + 1), joint 3's θ (3n + 2).
            let jac: Vec<[f64; 3]> = (0..27).map(|c| [c as f64, 0.0, 0.0]).collect();
            let mut out = Vec::new();
            e.extend(i, &[0.0; 3], &jac, &mut out);
            assert_eq!(out[27][0], 7.0 * tau[1].signum());
            assert_eq!(out[28][0], 20.0 * tau[2].signum());
            // What a true arm with this play reads in the pose the chain sees.
            let seen = angles_for(&arm, &physics, q);
            let back = readings_for(&arm, &physics, &seen);
            assert!(back.iter().zip(q).all(|(a, b)| (a - b).abs() < 1e-12));
        }
        // A vertical base axis carries no torque: its play moves nothing.
        arm = DhParams::paper_nominal();
        let base = Physics {
            backlash: vec![Some(play)],
            gravity: None,
            ..masses
        };
        let pose = [0.3, -0.4, 0.7, 0.2, -0.3, 0.5];
        assert_eq!(angles_for(&arm, &base, &pose), pose.to_vec());
    }

    /// A known direction of approach decides the flank in place of the
    /// torque's sign — also for a joint gravity does not load (the vertical
    /// base axis) — and a `0` falls back to the torque: the correction and
    /// the fitted column follow it.
    #[test]
    fn a_known_approach_decides_the_flank() {
        use crate::corrections::{Mass, gravity};
        let arm = DhParams::paper_nominal();
        let play = 0.02f64.to_radians();
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            backlash: vec![Some(play), Some(play), None, None, None, None],
            ..Physics::default()
        };
        let q = [
            [0.1, 0.7, 0.3, -0.2, 0.5, 1.0],
            [0.4, 0.9, 0.1, 0.2, -0.5, 2.0],
        ];
        let raw = PreparedPoses::for_shape(arm.shape().unwrap(), &q).unwrap();
        // Pose 0: joint 1 approached from below, joint 2 from above; pose
        // 1: joint 1 from above, joint 2 not known.
        let approach = [1, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 0];
        let conditions = Conditions {
            approach: Some(&approach),
            ..Conditions::default()
        };
        let fit = Beyond {
            backlash: vec![0, 1],
            ..Beyond::default()
        };
        let e = Effects::new(&arm, &physics, &fit, &raw, conditions).unwrap();
        let plain = Effects::new(&arm, &physics, &fit, &raw, Conditions::default()).unwrap();
        for (i, q) in q.iter().enumerate() {
            let mut tau = [0.0; 6];
            gravity::torques(&arm, &physics, q, &mut tau);
            assert_eq!(tau[0], 0.0, "the vertical base axis is not loaded");
            assert!(tau[1].abs() > 1.0, "{tau:?}");
            let gravity_side = tau[1].signum();
            let (want0, want1) = if i == 0 {
                (1.0, -1.0)
            } else {
                (-1.0, gravity_side)
            };
            let turned = |e: &Effects, j: usize| {
                let (c, s) = e.poses.column_trig(j);
                (c[i], s[i])
            };
            for (j, want) in [(0, want0), (1, want1)] {
                let t = q[j] + play * want;
                let (c, s) = turned(&e, j);
                assert!((c - t.cos()).abs() < 1e-15 && (s - t.sin()).abs() < 1e-15);
            }
            // Without the column the base floats and the shoulder rests
            // on the gravity side.
            assert_eq!(turned(&plain, 0), (q[0].cos(), q[0].sin()));
            let t = q[1] + play * gravity_side;
            assert!((turned(&plain, 1).0 - t.cos()).abs() < 1e-15);
            let jac: Vec<[f64; 3]> = (0..27).map(|c| [c as f64, 0.0, 0.0]).collect();
            let mut out = Vec::new();
            e.extend(i, &[0.0; 3], &jac, &mut out);
            assert_eq!((out[27][0], out[28][0]), (18.0 * want0, 19.0 * want1));
        }
    }

    /// Encoder harmonics and a compliance are models of an angle: refused
    /// on a prismatic joint, with the joint named; allowed on the others.
    #[test]
    fn a_slides_angle_models_are_refused() {
        let arm = sliding();
        let raw = poses(&arm);
        let none = Conditions::default();
        let harmonic = |joint| Physics {
            harmonics: vec![Harmonic {
                joint,
                order: 1,
                sin: 1e-5,
                cos: 0.0,
            }],
            ..Physics::default()
        };
        let e = Effects::new(&arm, &harmonic(1), &Beyond::default(), &raw, none).unwrap_err();
        assert_eq!(
            e,
            "joint 2 is prismatic: encoder harmonics are a model of a revolute joint's angle"
        );
        assert!(Effects::new(&arm, &harmonic(2), &Beyond::default(), &raw, none).is_ok());
        let fit = Beyond {
            compliance: vec![1],
            ..Beyond::default()
        };
        let e = Effects::new(&arm, &Physics::default(), &fit, &raw, none).unwrap_err();
        assert!(
            e.starts_with("joint 2 is prismatic: the compliance model"),
            "{e}"
        );
        let fit = Beyond {
            harmonics: vec![(1, 2)],
            ..Beyond::default()
        };
        assert!(Effects::new(&arm, &Physics::default(), &fit, &raw, none).is_err());
        // The revolute joints of a mixed chain keep their compliance.
        let fit = Beyond {
            compliance: vec![2],
            ..Beyond::default()
        };
        let physics = Physics {
            link_masses: vec![Some(crate::corrections::Mass::at_middle(1.0)); 6],
            ..Physics::default()
        };
        let e = Effects::new(&arm, &physics, &fit, &raw, none).unwrap();
        assert_eq!(e.poses.shape(), "RPRRRR".parse::<ChainShape>().ok());
    }

    /// The free columns the kernel hands over for [`Effects::free_plan`]'s
    /// chain columns, finished by [`Effects::finish_free`], are those picked
    /// out of [`Effects::extend`], to the bit: every kind of correction (a
    /// joint's, the expansion, the drift's axes), free columns out of order
    /// with geometry and corrections mixed and a partial last group; on the
    /// inlined 6R loop (no transform after the chain), with the transform
    /// (the fallback), and on a chain with a slide.
    #[test]
    fn free_columns_finished_are_those_extended() {
        use crate::corrections::Mass;
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(1.5)); 6],
            probe_mass: Some(Mass::at_middle(0.4)),
            gravity: Some([0.2, -0.4, -1.0]),
            compliance: vec![None, Some(2e-5), Some(1e-5), None, None, None],
            ..Physics::default()
        };
        // At the fit's point: the expansion's column is of the position
        // before the drift moved it.
        let moving = Physics {
            cte_per_k: Some(8e-6),
            drift_mm_per_h: Some([0.02, -0.01, 0.03]),
            ..physics.clone()
        };
        let n = 11;
        let q: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..6).map(|j| ((i * 5 + j) as f64 * 0.71).sin()).collect())
            .collect();
        let t: Vec<f64> = (0..n).map(|i| 15.0 + i as f64).collect();
        let h: Vec<f64> = (0..n).map(|i| 600.0 * i as f64).collect();
        let conditions = Conditions {
            temperature_c: Some(&t),
            time_s: Some(&h),
            approach: None,
        };
        let geometric = Beyond {
            compliance: vec![1, 2],
            harmonics: vec![(3, 1), (0, 2)],
            backlash: vec![4],
            ..Beyond::default()
        };
        let all = Beyond {
            thermal: true,
            drift: true,
            ..geometric.clone()
        };
        // The slide's play moves it as its offset `d` does; it has no
        // compliance.
        let slide = Physics {
            compliance: vec![None, None, Some(1e-5), None, None, None],
            ..moving.clone()
        };
        let slides = Beyond {
            compliance: vec![2],
            backlash: vec![1, 4],
            ..all.clone()
        };
        for (arm, physics, fit) in [
            (DhParams::paper_nominal(), &physics, &geometric),
            (DhParams::paper_nominal(), &moving, &all),
            (sliding(), &slide, &slides),
        ] {
            let raw = PreparedPoses::for_shape(arm.shape().unwrap(), &q).unwrap();
            let e = Effects::new(&arm, physics, fit, &raw, conditions).unwrap();
            assert_eq!(e.poses.post().is_some(), fit.thermal);
            let k = ArmKernel::new(&arm).unwrap();
            let params = k.param_count();
            let free: Vec<usize> = (0..params + e.kinds.len())
                .filter(|&c| c >= params || c % 4 != 2)
                .rev()
                .collect();
            assert_ne!(free.len() % LANES, 0);
            let mut want = Vec::new();
            let mut ext = Vec::new();
            k.for_each_jacobian(&e.poses, 1..n, |i, pos, jac| {
                e.extend(i, pos, jac, &mut ext);
                let cols: Vec<[u64; 3]> = free.iter().map(|&c| ext[c].map(f64::to_bits)).collect();
                want.push((i, *pos, cols));
            })
            .unwrap();
            let plan = e.free_plan(&free, params);
            let mut got = Vec::new();
            k.for_each_free_jacobian(&e.poses, 1..n, &plan.chain, |i, pos, mut rows| {
                e.finish_free(&plan, i, pos, rows.each_mut().map(|r| &mut **r));
                let [x, y, z] = rows.map(|r| r.as_flattened());
                let cols: Vec<[u64; 3]> = (0..free.len())
                    .map(|u| [x[u], y[u], z[u]].map(f64::to_bits))
                    .collect();
                got.push((i, *pos, cols));
            })
            .unwrap();
            assert_eq!(got, want, "{fit:?}");
        }
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn corrections_effects_angles_for() {
        use crate::corrections::{Harmonic, Physics, angles_for, readings_for};
        use crate::params::DhParams;
        let arm = DhParams::paper_nominal();
        let mut physics = Physics::default();
        physics.harmonics.push(Harmonic {
            joint: 1,
            order: 1,
            sin: 2e-4,
            cos: -1e-4,
        });
        let pose = [0.1, -0.4, 0.7, 0.2, -0.3, 0.5];
        let q = readings_for(&arm, &physics, &pose);
        assert!(
            (q[1] - pose[1]).abs() > 1e-5,
            "the harmonic moves joint 2's reading"
        );
        let back = angles_for(&arm, &physics, &q);
        assert!(back.iter().zip(&pose).all(|(a, b)| (a - b).abs() < 1e-15));
    }
}
