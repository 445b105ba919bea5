//! `aacmm simulate`: a calibration campaign with a known true arm — what the
//! encoders would read, the true sockets, reference lengths and the true arm
//! — written so that a calibration can be checked against the truth.

use std::path::{Path, PathBuf};

use aacmm_core::domain::Arm;
use aacmm_core::error::quoted;
use aacmm_core::io::{read_arm, source_name};
use aacmm_core::params::ChainShape;

use super::report;
use aacmm_core::simulate::{
    CAMPAIGN_FILE, CampaignSettings, DEFAULT_LENGTH_SIGMA_MM, DEFAULT_TWIST_SIGMA_DEG,
    DEFAULT_ZERO_SIGMA_DEG, ErrorModel, LENGTHS_FILE, POSES_FILE, SOCKETS_FILE, SimError,
    SocketPlan, TRUE_ARM_FILE, pair_count, random_arm, seeds, simulate_observed, write_campaign,
};

/// The nominal arm `--chain` draws, written into --out.
const NOMINAL_FILE: &str = "nominal.toml";
use anyhow::{Result, anyhow, bail};
use clap::{ArgGroup, ValueEnum};

use crate::output::note;
use crate::paths::{Input, check_output_dir};

/// Default number of reference lengths (fewer if the sockets make fewer pairs).
const DEFAULT_REFERENCE_LENGTHS: usize = 3;

/// Simulate a calibration campaign: a true arm touches K sockets N times each
/// in different articulations; writes poses.csv (encoder readings, degrees),
/// lengths.csv (mm), sockets.csv (true centres, mm), true_arm.toml and
/// campaign.toml (every setting and the seed) into --out. Same seed, same bytes.
#[derive(clap::Args)]
#[command(group(ArgGroup::new("nominal").required(true).args(["arm", "chain"])))]
#[command(group(ArgGroup::new("truth").required(true).args(["true_arm", "errors"])))]
#[command(group(ArgGroup::new("where").required(true).multiple(true).args(["sockets", "sockets_file", "positions", "spheres"])))]
pub struct Args {
    /// Nominal arm file (TOML, 1 to 12 joints, revolute or prismatic); its
    /// joint limits, if any, bound every simulated reading (a prismatic
    /// joint needs its stroke).
    #[arg(long, value_name = "NOMINAL.toml")]
    arm: Option<PathBuf>,
    /// Instead of --arm, a random nominal arm of this chain: one letter per
    /// joint from the base, R revolute, P prismatic (`PRRRRRR`: a robot on
    /// a track; 1 to 12 joints), drawn from --seed and written to
    /// nominal.toml in --out (twists ±90°, a robot's reach, strokes of
    /// 400–1200 mm).
    #[arg(long, value_name = "JOINTS", value_parser = chain_shape)]
    chain: Option<ChainShape>,
    /// True arm file (same joint count as the nominal); exclusive with --errors.
    #[arg(long = "true", value_name = "TRUE.toml")]
    true_arm: Option<PathBuf>,
    /// Errors that make the true arm from the nominal.
    #[arg(long, value_enum, value_name = "MODEL")]
    errors: Option<Errors>,
    /// Multiplier on the random models' default standard deviations [default: 1].
    #[arg(
        long,
        value_name = "X",
        requires = "errors",
        allow_negative_numbers = true
    )]
    error_scale: Option<f64>,
    /// Number of sockets, spread over the true arm's reachable volume
    /// (near/middle/far from the base axis, at 30–80 % of its reach).
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    sockets: Option<usize>,
    /// Socket centres from a point file (CSV `point,x,y,z`, mm) instead of --sockets.
    #[arg(long, value_name = "FILE", conflicts_with = "sockets")]
    sockets_file: Option<PathBuf>,
    /// Touches per socket (at least 3), each a different articulation (some
    /// joint at least 20° away from every other touch of the socket).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    poses: Option<usize>,
    /// Also (or instead) a laser-tracker campaign: N random poses (within
    /// the joint limits) per instrument frame, seen from random stations
    /// 2–4 m away; writes positions.csv and the true frames into
    /// true_arm.toml.
    #[arg(long, value_name = "N")]
    positions: Option<usize>,
    /// Also (or instead) points probed on reference spheres: N placements
    /// through the volume, each probed at ISO 10360-5's 25 points (pole, 4
    /// at 22.5° below it, 8 at 45°, 4 at 67.5°, 8 on the equator) of its
    /// upper hemisphere by the true arm, with --encoder-noise and
    /// --probe-noise; writes spheres.csv. The probe ball is the arm file's
    /// `[probe] ball_diameter_mm` (6 mm when it states none).
    #[arg(long, value_name = "N")]
    spheres: Option<usize>,
    /// The spheres' diameter, mm.
    #[arg(long, value_name = "MM", requires = "spheres", default_value_t = aacmm_core::simulate::DEFAULT_SPHERE_DIAMETER_MM)]
    sphere_diameter: f64,
    /// With --spheres, also A placements for `verify`'s L_Dia (`L1`, …): a
    /// sphere probed in five articulations (elbow and wrist turned between
    /// them), five points each with the probe pointing about the same way;
    /// spheres.csv then has an `articulation` column (1 on every other
    /// placement's rows).
    #[arg(long, value_name = "A", requires = "spheres", default_value_t = 0)]
    articulated: usize,
    /// With --spheres, also B positions of a ball bar for `verify`'s E_Uni
    /// (placements `B1a`/`B1b`, …, 25 points each, the bar in a random
    /// position and orientation); writes bar_lengths.csv naming each pair
    /// with its true centre distance.
    #[arg(long, value_name = "B", requires = "spheres", default_value_t = 0)]
    ball_bar: usize,
    /// With --spheres alone (no sockets, no positions): each of the arm
    /// file's `[[tool]]` styli probes N placements of its own too (`S1.NAME`,
    /// …, the `tool` column of spheres.csv), with its `ball_diameter_mm` (the
    /// probe's when it states none) at its true offset — each 0.3 mm off its
    /// nominal per axis, written to true_arm.toml: what `aacmm probe` and a
    /// calibration of several probes are tried on.
    #[arg(long, requires = "spheres", conflicts_with_all = ["sockets", "sockets_file", "positions"])]
    sphere_tools: bool,
    /// The ball bar's length, centre to centre, mm.
    #[arg(long, value_name = "MM", requires = "ball_bar", default_value_t = aacmm_core::simulate::DEFAULT_BAR_LENGTH_MM)]
    bar_length: f64,
    /// --positions seen at K markers on one body instead of the probe
    /// (SMRs on an end effector): each pose seen at every marker, written
    /// as the `tool` column of positions.csv. The markers are the arm
    /// file's `[[tool]]` when it lists some (then --tools may be left out);
    /// else K drawn on the flange, 40–90 mm off the last axis, written with
    /// the nominal arm to nominal.toml. The true markers (each 0.5 mm off
    /// its nominal per axis, or a --true arm's `[[tool]]`) go into
    /// true_arm.toml.
    #[arg(long, value_name = "K", requires = "positions", value_parser = clap::value_parser!(u32).range(1..=64))]
    tools: Option<u32>,
    /// Instrument stations of --positions, each with its own random pose.
    #[arg(long, value_name = "F", default_value_t = 1, requires = "positions")]
    frames: usize,
    /// Noise of --positions per coordinate: `A` mm or `A+B/m` (a tracker's
    /// `0.015+0.006/m`, the default).
    #[arg(long, value_name = "MM[+MM/m]", requires = "positions", value_parser = super::shared_flags::position_noise)]
    position_noise: Option<(f64, Option<f64>)>,
    /// Temperatures of --positions, drawn uniformly in LOW:HIGH °C, written
    /// as a `temperature` column: a true arm stating `cte_per_k` grows with
    /// them (from 20 °C).
    #[arg(long, value_name = "LOW:HIGH", requires = "positions", value_parser = temperature_range)]
    temperature: Option<[f64; 2]>,
    /// Rows of --positions taken evenly over this many hours, written as a
    /// `time` column (s).
    #[arg(long, value_name = "H", requires = "positions")]
    session_hours: Option<f64>,
    /// Each joint approaches each pose of --positions from a random side,
    /// written as an `approach` column (`+-+…`, one sign per joint): the
    /// true arm's backlash rests on that flank rather than the one gravity
    /// presses.
    #[arg(long, requires = "positions")]
    approach: bool,
    /// The tool's orientation seen too (a 6-D target): written as the
    /// `qw,qx,qy,qz` columns of positions.csv, the true tool frame in each
    /// row's frame turned by --orientation-noise.
    #[arg(long, requires = "positions")]
    orientation: bool,
    /// σ of --orientation per axis, degrees (a tracker's 6-D target's,
    /// 0.01, the default).
    #[arg(
        long,
        value_name = "DEG",
        requires = "orientation",
        default_value_t = 0.01
    )]
    orientation_noise: f64,
    /// The largest angle of the 6-D target's random mount on the flange,
    /// degrees: its axis uniform on the sphere, its angle uniform in
    /// [0, DEG] (180, the default: any way; 0: mounted square). Written in
    /// true_arm.toml as `[mount]`.
    #[arg(
        long,
        value_name = "DEG",
        requires = "orientation",
        default_value_t = 180.0,
        value_parser = mount_angle
    )]
    mount_deg: f64,
    /// A drift of the true arm's base against the instrument over the
    /// session, `X,Y,Z` mm/h (needs --session-hours).
    #[arg(long, value_name = "X,Y,Z", requires = "session_hours", value_parser = drift_vector)]
    drift: Option<[f64; 3]>,
    /// Seed of every random draw (0 to 2^63 - 1); recorded in campaign.toml.
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(0..=i64::MAX as u64))]
    seed: u64,
    /// Standard deviation of the Gaussian noise on each encoder reading, degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    encoder_noise: f64,
    /// Standard deviation of the probe seating per axis, mm (the ball never
    /// sits twice in exactly the same place).
    #[arg(
        long,
        value_name = "MM",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    probe_noise: f64,
    /// Number of reference lengths (distinct socket pairs, preferring long
    /// ones) [default: 3, or the number of pairs if fewer; 0 = none].
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    reference_lengths: Option<usize>,
    /// Standard uncertainty of the reference lengths, mm: the recorded
    /// distances get Gaussian noise of this size and lengths.csv states it.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    length_uncertainty: Option<f64>,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

/// The error models of `--errors`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Errors {
    /// The paper's identified errors (Table 2; 6-joint arms only).
    Paper,
    /// Gaussian errors on every parameter: lengths σ 0.4 mm, twists 0.07°,
    /// zero offsets 0.45° (the RMS of Table 2), times --error-scale.
    Random,
    /// A newly assembled arm: random errors, but zero offsets anywhere in ±180°.
    Assembled,
}

pub fn run(args: Args) -> Result<()> {
    check_paths(&args)?;
    let stated = with_markers(&args, nominal_arm(&args)?)?;
    let nominal = with_ball(&args, &stated);
    let joints = nominal.params.joint_count();
    let errors = error_model(&args)?;
    if args.sockets.is_none() && args.sockets_file.is_none() {
        let truth = match args.positions {
            Some(_) => Some(tracker(&args, &nominal, &errors, None)?),
            None => None,
        };
        return spheres(&args, &stated, &errors, truth.as_ref());
    }
    let (sockets, file) = socket_plan(&args)?;
    let located = |e| flag_error(e, file.as_ref());
    let settings = campaign_settings(&args, errors.clone(), sockets);
    settings.validate(joints).map_err(located)?;

    // Progress on a terminal: a thousand sockets take half a minute.
    let mut bar = super::progress::Bar::new();
    let campaign = simulate_observed(&nominal, &settings, &mut |f| bar.show("simulate", f));
    drop(bar);
    let campaign = campaign.map_err(located)?;
    let written = write_campaign(&args.out, &campaign, &settings)?;
    describe(&args, &nominal, &settings, &campaign, &written)?;
    if args.positions.is_some() {
        tracker(&args, &nominal, &errors, Some(&campaign.true_arm))?;
    }
    spheres(&args, &stated, &errors, Some(&campaign.true_arm))
}

/// The nominal arm a campaign with --spheres is drawn from: `stated` with
/// the ball it probes with ([`DEFAULT_BALL_DIAMETER_MM`] where the arm file
/// states none), so that true_arm.toml says the diameter spheres.csv was
/// made with; `stated` itself without --spheres.
fn with_ball(args: &Args, stated: &Arm) -> Arm {
    let mut arm = stated.clone();
    if args.spheres.is_some() {
        arm.ball_diameter_mm = arm.ball_diameter_mm.or(Some(DEFAULT_BALL_DIAMETER_MM));
    }
    arm
}

/// The ball diameter `simulate --spheres` probes with when the arm file
/// states none, mm.
const DEFAULT_BALL_DIAMETER_MM: f64 = 6.0;

/// The sphere campaign of --spheres (nothing without it): of `truth` (the
/// touch or tracker campaign's true arm) or of a true arm drawn from
/// `errors` about `nominal` (as the arm file states it: the note says when
/// it states no ball), written to true_arm.toml; spheres.csv.
fn spheres(args: &Args, nominal: &Arm, errors: &ErrorModel, truth: Option<&Arm>) -> Result<()> {
    use aacmm_core::io::spheres::write_spheres;
    use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml};
    use aacmm_core::simulate::{SPHERES_FILE, SphereSettings, simulate_spheres};
    let Some(placements) = args.spheres else {
        return Ok(());
    };
    let ball = nominal.ball_diameter_mm.unwrap_or(DEFAULT_BALL_DIAMETER_MM);
    let settings = SphereSettings {
        placements,
        diameter_mm: args.sphere_diameter,
        ball_diameter_mm: ball,
        encoder_rad: args.encoder_noise.to_radians(),
        probe_mm: args.probe_noise,
        seed: args.seed,
    };
    let located = |e| anyhow!("--spheres: {e}");
    let (truth, campaign) = match truth {
        Some(t) => (
            t.clone(),
            simulate_spheres(t, &settings.for_campaign()).map_err(located)?,
        ),
        None => {
            let (mut truth, campaign) = aacmm_core::simulate::simulate_sphere_campaign(
                &with_ball(args, nominal),
                errors,
                &settings,
            )
            .map_err(|e| flag_error(e, None))?;
            if args.sphere_tools {
                // From a stream of their own: the arm and its points are
                // those of the campaign without them.
                let seed = seeds::of(args.seed, seeds::SPHERE_TOOLS);
                truth.tools = aacmm_core::simulate::perturbed_tools(&nominal.tools, 0.3, seed);
            }
            std::fs::create_dir_all(&args.out)
                .map_err(|e| anyhow!("--out {}: cannot create: {e}", args.out.display()))?;
            let text = arm_to_toml(&truth, LengthUnit::Mm, AngleUnit::Deg);
            let arm_path = args.out.join(TRUE_ARM_FILE);
            write_file(&arm_path, text.as_bytes())?;
            note(format_args!("wrote {}", arm_path.display()))?;
            (truth, campaign)
        }
    };
    let (rows, lengths) = acceptance_placements(args, &truth, campaign, &settings)?;
    let rows = match args.sphere_tools {
        true => {
            let settings = settings.for_campaign();
            let located = |e| flag_error(e, None);
            let rows = aacmm_core::simulate::with_tool_placements(&truth, rows, &settings)
                .map_err(located)?
                .spheres;
            let names: Vec<&str> = truth.tools.iter().map(|t| t.name.as_str()).collect();
            note(format_args!(
                "--sphere-tools: {placements} placements by each stylus too ({}; S1.NAME, …), \
                 at its true offset in {TRUE_ARM_FILE}",
                names.join(", ")
            ))?;
            rows
        }
        false => rows,
    };
    let path = args.out.join(SPHERES_FILE);
    let mut text = Vec::new();
    write_spheres(&mut text, &rows, AngleUnit::Deg)?;
    write_file(&path, &text)?;
    note(format_args!(
        "spheres: {placements} placements of {} mm, 25 points each, probe ball {ball} mm{}; \
         seed {}",
        args.sphere_diameter,
        match nominal.ball_diameter_mm {
            Some(_) => "",
            None => " (the arm file states none: add `ball_diameter_mm = 6` to its [probe])",
        },
        args.seed
    ))?;
    note(format_args!("wrote {}", path.display()))?;
    if let Some(lengths) = lengths {
        use aacmm_core::simulate::BAR_LENGTHS_FILE;
        let path = args.out.join(BAR_LENGTHS_FILE);
        let mut text = Vec::new();
        aacmm_core::io::write_lengths(&mut text, &lengths)?;
        write_file(&path, &text)?;
        note(format_args!(
            "ball bar: {} positions of {} mm (placements B1a/B1b, …); wrote {}",
            args.ball_bar,
            args.bar_length,
            path.display()
        ))?;
    }
    Ok(())
}

/// The rows of spheres.csv: `campaign`'s, with --articulated's and
/// --ball-bar's placements when asked (the bar's lengths too).
fn acceptance_placements(
    args: &Args,
    truth: &Arm,
    campaign: aacmm_core::simulate::SphereCampaign,
    settings: &aacmm_core::simulate::SphereSettings,
) -> Result<(
    aacmm_core::domain::Spheres,
    Option<Vec<aacmm_core::domain::ReferenceLength>>,
)> {
    use aacmm_core::simulate::{AcceptanceSettings, with_acceptance};
    if args.articulated == 0 && args.ball_bar == 0 {
        return Ok((campaign.spheres, None));
    }
    let more = AcceptanceSettings {
        articulated: args.articulated,
        bar_positions: args.ball_bar,
        bar_length_mm: args.bar_length,
    };
    let out = with_acceptance(truth, campaign, settings, &more).map_err(|e| flag_error(e, None))?;
    if args.articulated > 0 {
        note(format_args!(
            "L_Dia: {} placements (L1, …) of five articulations × five points",
            args.articulated
        ))?;
    }
    Ok((out.spheres, (args.ball_bar > 0).then_some(out.lengths)))
}

/// The tracker campaign of --positions: of `truth` (the touch campaign's
/// true arm) or of a true arm drawn from `errors`; positions.csv and
/// true_arm.toml with the true frames.
fn tracker(args: &Args, nominal: &Arm, errors: &ErrorModel, truth: Option<&Arm>) -> Result<Arm> {
    use aacmm_core::io::frames::frames_to_toml;
    use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml, positions::write_positions};
    use aacmm_core::simulate::{POSITIONS_FILE, PositionSettings, true_frames};
    let Some(poses) = args.positions else {
        bail!("give --sockets K, --sockets-file FILE or --positions N");
    };
    let (a, b) = args.position_noise.unwrap_or((0.015, Some(0.006)));
    let settings = PositionSettings {
        poses,
        frames: args.frames,
        noise: aacmm_core::residuals::Noise {
            position_mm: Some(a),
            position_mm_per_m: b,
            ..Default::default()
        },
        seed: args.seed,
    };
    let conditions = aacmm_core::simulate::ConditionSettings {
        temperature_c: args.temperature,
        session_h: args.session_hours,
        approach: args.approach,
    };
    let session =
        |t: &Arm| aacmm_core::simulate::simulate_session(t, &settings, &conditions, args.drift);
    let (truth, campaign) = match truth {
        Some(t) => (t.clone(), session(t)),
        None if conditions != Default::default() => {
            use aacmm_core::simulate::simulate_tracker_session;
            match simulate_tracker_session(nominal, errors, &settings, &conditions, args.drift) {
                Ok((t, c)) => (t, Ok(c)),
                Err(e) => return Err(flag_error(e, None)),
            }
        }
        None => match aacmm_core::simulate::simulate_tracker(nominal, errors, &settings) {
            Ok((t, c)) => (t, Ok(c)),
            Err(e) => return Err(flag_error(e, None)),
        },
    };
    let mut campaign = campaign.map_err(|e| anyhow!("--positions: {e}"))?;
    let mut truth = truth;
    let mount = orient(args, &truth, &mut campaign)?;
    if !nominal.tools.is_empty() {
        see_markers(args, nominal, &mut truth, &mut campaign, &settings.noise)?;
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| anyhow!("--out {}: cannot create: {e}", args.out.display()))?;
    let path = args.out.join(POSITIONS_FILE);
    let mut text = Vec::new();
    write_positions(&mut text, &campaign.positions, AngleUnit::Deg)?;
    write_file(&path, &text)?;
    let true_arm = arm_to_toml(&truth, LengthUnit::Mm, AngleUnit::Deg)
        + &frames_to_toml(&true_frames(&campaign))
        + &mount.map_or_else(String::new, |m| {
            aacmm_core::io::frames::mount_to_toml(&aacmm_core::io::frames::MountRecord {
                rotation_deg: m.map(f64::to_degrees),
                small_rotation_sigma_deg: None,
            })
        });
    let arm_path = args.out.join(TRUE_ARM_FILE);
    write_file(&arm_path, true_arm.as_bytes())?;
    let mut turned = if args.orientation {
        format!(", orientations {}° per axis", args.orientation_noise)
    } else {
        String::new()
    };
    if !truth.tools.is_empty() {
        turned += &format!(", each seen at {} marker(s)", truth.tools.len());
    }
    note(format_args!(
        "tracker: {poses} poses in each of {} frame(s), noise {a} mm{}{turned}; seed {}",
        args.frames,
        b.map(|b| format!(" + {b} mm/m")).unwrap_or_default(),
        args.seed
    ))?;
    note(format_args!("wrote {}", path.display()))?;
    note(format_args!(
        "wrote {} (with the true frames)",
        arm_path.display()
    ))?;
    Ok(truth)
}

/// With --orientation, `campaign`'s rows given the true tool frame's
/// orientation (a random mount, returned); nothing without.
fn orient(
    args: &Args,
    truth: &Arm,
    campaign: &mut aacmm_core::simulate::PositionCampaign,
) -> Result<Option<[f64; 3]>> {
    if !args.orientation {
        return Ok(None);
    }
    // Its own stream (the truth has the seed, the positions the next):
    // the positions are those of a campaign without orientations.
    // The mount from a stream of its own too: --mount-deg 0 gives the
    // orientations of a target mounted square, whatever the seed.
    let settings = aacmm_core::simulate::OrientationSettings {
        mount: aacmm_core::simulate::random_mount(
            args.mount_deg.to_radians(),
            seeds::of(args.seed, seeds::MOUNT),
        ),
        sigma_rad: args.orientation_noise.to_radians(),
        seed: seeds::of(args.seed, seeds::ORIENTATIONS),
    };
    campaign.positions = (aacmm_core::simulate::orient_positions(
        truth,
        &campaign.positions,
        &campaign.frames,
        &settings,
    ))
    .map_err(|e| anyhow!("--orientation: {e}"))?;
    Ok(Some(settings.mount))
}

/// `campaign`'s poses seen at the markers of `nominal` instead of the
/// probe: the true markers `truth`'s own when a --true arm lists them, else
/// each 0.5 mm off its nominal per axis.
fn see_markers(
    args: &Args,
    nominal: &Arm,
    truth: &mut Arm,
    campaign: &mut aacmm_core::simulate::PositionCampaign,
    noise: &aacmm_core::residuals::Noise,
) -> Result<()> {
    use aacmm_core::simulate::{perturbed_tools, seen_at_markers};
    // The markers' offsets and noise from streams of their own: the poses
    // are those of a campaign without markers.
    if args.true_arm.is_none() || truth.tools.is_empty() {
        truth.tools = perturbed_tools(
            &nominal.tools,
            0.5,
            seeds::of(args.seed, seeds::MARKER_ERRORS),
        );
    }
    campaign.positions = seen_at_markers(
        truth,
        campaign,
        noise,
        1.0,
        seeds::of(args.seed, seeds::MARKER_NOISE),
    )
    .map_err(|e| anyhow!("--tools: {e}"))?;
    Ok(())
}

/// `--mount-deg`'s value: an angle in [0, 180] degrees.
fn mount_angle(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (0.0..=180.0).contains(&v) => Ok(v),
        Ok(v) => Err(format!(
            "{v}: the mount's largest angle is 0 to 180 degrees"
        )),
        Err(e) => Err(format!("{text}: {e}")),
    }
}

/// `--chain`'s value: a chain shape such as `PRRRRRR`.
fn chain_shape(text: &str) -> Result<ChainShape, String> {
    text.parse::<ChainShape>().map_err(|e| e.to_string())
}

/// The nominal arm: --arm's file, or --chain's random arm, written to
/// nominal.toml in --out so that the campaign can be calibrated against it.
fn nominal_arm(args: &Args) -> Result<Arm> {
    use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml};
    match (&args.arm, args.chain) {
        (Some(path), _) => {
            let (nominal, warnings) = read_arm(path)?;
            report(&warnings)?;
            Ok(nominal)
        }
        (None, Some(shape)) => {
            let nominal = random_arm(shape, args.seed);
            std::fs::create_dir_all(&args.out)
                .map_err(|e| anyhow!("--out {}: cannot create: {e}", args.out.display()))?;
            let text = arm_to_toml(&nominal, LengthUnit::Mm, AngleUnit::Deg);
            let path = args.out.join(NOMINAL_FILE);
            write_file(&path, text.as_bytes())?;
            note(format_args!("wrote {} (--chain {shape})", path.display()))?;
            Ok(nominal)
        }
        (None, None) => bail!("give --arm NOMINAL.toml or --chain JOINTS"),
    }
}

/// `nominal` with `--tools K` markers drawn on its flange (written with it
/// to nominal.toml) when it lists none; as it is otherwise.
fn with_markers(args: &Args, mut nominal: Arm) -> Result<Arm> {
    use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml};
    use aacmm_core::simulate::random_tools;
    let Some(k) = args.tools.filter(|_| nominal.tools.is_empty()) else {
        return Ok(nominal);
    };
    nominal.tools = random_tools(k as usize, seeds::of(args.seed, seeds::MARKERS));
    std::fs::create_dir_all(&args.out)
        .map_err(|e| anyhow!("--out {}: cannot create: {e}", args.out.display()))?;
    let path = args.out.join(NOMINAL_FILE);
    let text = arm_to_toml(&nominal, LengthUnit::Mm, AngleUnit::Deg);
    write_file(&path, text.as_bytes())?;
    note(format_args!("wrote {} (with {k} markers)", path.display()))?;
    Ok(nominal)
}

/// The nominal arm's name in messages and campaign.toml: --arm's file, or
/// the nominal.toml --chain writes.
fn nominal_name(args: &Args) -> String {
    match &args.arm {
        Some(path) => source_name(path),
        None => args.out.join(NOMINAL_FILE).display().to_string(),
    }
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    aacmm_core::io::write_atomic(path, bytes)
        .map_err(|e| anyhow!("{}: cannot write: {e}", path.display()))
}

/// --out may not hold an input, nor (without --force) earlier results.
fn check_paths(args: &Args) -> Result<()> {
    let mut inputs: Vec<Input> = args.arm.iter().map(|p| ("--arm", p.as_path())).collect();
    inputs.extend(args.true_arm.as_deref().map(|p| ("--true", p)));
    inputs.extend(args.sockets_file.as_deref().map(|p| ("--sockets-file", p)));
    let outputs = [
        POSES_FILE,
        LENGTHS_FILE,
        SOCKETS_FILE,
        TRUE_ARM_FILE,
        CAMPAIGN_FILE,
        aacmm_core::simulate::POSITIONS_FILE,
        aacmm_core::simulate::SPHERES_FILE,
        if args.chain.is_some() || args.tools.is_some() {
            NOMINAL_FILE
        } else {
            CAMPAIGN_FILE
        },
    ];
    check_output_dir("--out", &args.out, &outputs, &inputs, args.force)
}

/// The true arm: a file (--true) or an error model (--errors).
fn error_model(args: &Args) -> Result<ErrorModel> {
    Ok(match (&args.true_arm, args.errors) {
        (Some(path), _) => {
            let (arm, warnings) = read_arm(path)?;
            report(&warnings)?;
            ErrorModel::File { arm }
        }
        (None, Some(Errors::Paper)) => {
            if args.error_scale.is_some() {
                bail!(
                    "--error-scale: applies to --errors random|assembled, not to the paper's fixed errors"
                );
            }
            ErrorModel::Paper
        }
        (None, Some(model)) => {
            let scale = args.error_scale.unwrap_or(1.0);
            if let Err(why) = ErrorModel::check_scale(scale) {
                bail!("--error-scale: {why}");
            }
            ErrorModel::random(scale, model == Errors::Assembled)
        }
        (None, None) => bail!("give --true TRUE.toml or --errors paper|random|assembled"),
    })
}

/// Where the sockets are: spread (--sockets) or from a file
/// (--sockets-file, kept for messages).
fn socket_plan(args: &Args) -> Result<(SocketPlan, Option<SocketsFile>)> {
    Ok(match (&args.sockets_file, args.sockets) {
        (Some(path), _) => {
            let plan = SocketPlan::from_file(path)?;
            let file = SocketsFile::new(path, &plan);
            file.check_places(&plan)?;
            (plan, Some(file))
        }
        (None, Some(count)) => (SocketPlan::Spread { count }, None),
        (None, None) => bail!("give --sockets K or --sockets-file FILE"),
    })
}

/// The campaign's settings from the flags (not yet checked).
fn campaign_settings(args: &Args, errors: ErrorModel, sockets: SocketPlan) -> CampaignSettings {
    let count = sockets.count();
    let mut settings = CampaignSettings::new(args.seed, errors, count, args.poses.unwrap_or(0));
    settings.nominal_file = Some(nominal_name(args));
    settings.sockets = sockets;
    settings.encoder_noise_deg = args.encoder_noise;
    settings.probe_noise_mm = args.probe_noise;
    settings.reference_lengths = args
        .reference_lengths
        .unwrap_or_else(|| DEFAULT_REFERENCE_LENGTHS.min(pair_count(count)));
    settings.length_uncertainty_mm = args.length_uncertainty;
    settings
}

/// What was simulated and written, on stderr.
fn describe(
    args: &Args,
    nominal: &Arm,
    settings: &CampaignSettings,
    campaign: &aacmm_core::simulate::Campaign,
    written: &[PathBuf],
) -> Result<()> {
    let joints = nominal.params.joint_count();
    let count = settings.sockets.count();
    let st = &campaign.stats;
    note(format_args!(
        "nominal arm {} ({}, {joints} joints)",
        quoted(&nominal.name),
        nominal_name(args)
    ))?;
    note(format_args!(
        "true arm: {}",
        match &args.true_arm {
            Some(path) => format!("{} ({})", settings.errors.describe(), source_name(path)),
            None => settings.errors.describe(),
        }
    ))?;
    let placed = match &args.sockets_file {
        Some(path) => format!("from {}", source_name(path)),
        None => "spread over the reachable volume".to_string(),
    };
    note(format_args!(
        "{count} socket{} {placed}, {} touches each: {} poses ({} IK starts: {} not converged, \
         {} outside joint limits, {} too close to an earlier touch; largest residual {:.1e} mm)",
        if count == 1 { "" } else { "s" },
        settings.poses_per_socket,
        campaign.poses.len(),
        st.ik_starts,
        st.not_converged,
        st.outside_limits,
        st.too_close,
        st.max_residual_mm
    ))?;
    // A slide's scale has its own, fixed noise (said only where there is one).
    let slides = match nominal.params.has_prismatic() {
        true => format!(", slides {} mm", aacmm_core::simulate::SLIDE_NOISE_MM),
        false => String::new(),
    };
    note(format_args!(
        "noise: encoders {}°{slides}, probe seating {} mm; {} reference lengths{}; seed {}",
        settings.encoder_noise_deg,
        settings.probe_noise_mm,
        campaign.lengths.len(),
        settings
            .length_uncertainty_mm
            .map(|u| format!(" (uncertainty {u} mm)"))
            .unwrap_or_default(),
        settings.seed
    ))?;
    if campaign.lengths.is_empty() {
        note(
            "no reference lengths: lengths.csv not written (without one, the arm's scale cannot \
             be calibrated)",
        )?;
    }
    for path in written {
        note(format_args!("wrote {}", path.display()))?;
    }
    Ok(())
}

/// A `--sockets-file` and the line of each of its sockets, for messages.
struct SocketsFile {
    name: String,
    /// The sockets' labels, in order.
    labels: Vec<String>,
    /// Per socket, its line in the file (empty if it could not be told).
    lines: Vec<usize>,
}

impl SocketsFile {
    fn new(path: &Path, plan: &SocketPlan) -> SocketsFile {
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let mut lines = row_lines(&text);
        if lines.len() != plan.count() {
            lines.clear();
        }
        let labels = match plan {
            SocketPlan::Given { points, .. } => points.iter().map(|p| p.label.clone()).collect(),
            SocketPlan::Spread { .. } => Vec::new(),
        };
        SocketsFile {
            name: path.display().to_string(),
            labels,
            lines,
        }
    }

    /// `file:line` of socket `i`, or just the file.
    fn at(&self, i: usize) -> String {
        match self.lines.get(i) {
            Some(line) => format!("{}:{line}", self.name),
            None => self.name.clone(),
        }
    }

    /// `file:line` of the socket labelled `label`.
    fn at_label(&self, label: &str) -> String {
        match self.labels.iter().position(|l| l == label) {
            Some(i) => self.at(i),
            None => self.name.clone(),
        }
    }

    /// Two sockets at the same place would make a zero reference length and
    /// touches that cannot tell them apart.
    fn check_places(&self, plan: &SocketPlan) -> Result<()> {
        let (Some((i, j)), SocketPlan::Given { points, .. }) = (plan.same_place(), plan) else {
            return Ok(());
        };
        let (a, b) = (&points[i], &points[j]);
        let first = match self.lines.get(i) {
            Some(line) => format!("line {line}"),
            None => "earlier".to_string(),
        };
        bail!(
            "{}: field `point`: socket {} is at the same place as socket {} ({first}): \
             ({}, {}, {}) mm; every socket must be a different point",
            self.at(j),
            quoted(&b.label),
            quoted(&a.label),
            b.x,
            b.y,
            b.z
        )
    }
}

/// The 1-based lines of the data rows of a CSV file with a header, as the
/// io readers count them: blank lines and `#` comments are not rows.
fn row_lines(text: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            let t = l.trim_start_matches('\u{feff}').trim();
            !t.is_empty() && !t.starts_with('#')
        })
        .map(|(i, _)| i + 1)
        .skip(1)
        .collect()
}

/// A settings error in terms of the flag the user typed; a socket of a
/// sockets file is named by its file and line.
fn flag_error(e: SimError, file: Option<&SocketsFile>) -> anyhow::Error {
    if let (SimError::TooFewPoses { socket, .. }, Some(f)) = (&e, file) {
        return anyhow!("{}: {e}", f.at_label(socket));
    }
    let SimError::Setting { name, message } = &e else {
        return e.into();
    };
    if let (Some(f), "sockets.points") = (file, name.as_str()) {
        return anyhow!("--sockets-file {}: {message}", f.name);
    }
    let flag = match name.as_str() {
        "seed" => "--seed",
        "sockets" => "--sockets",
        "sockets.points" => "--sockets-file",
        "poses_per_socket" => "--poses",
        "encoder_noise_deg" => "--encoder-noise",
        "probe_noise_mm" => "--probe-noise",
        "reference_lengths" => "--reference-lengths",
        "length_uncertainty_mm" => "--length-uncertainty",
        "sphere_tools" => "--sphere-tools",
        n if n.starts_with("errors.") => "--error-scale",
        _ => return e.into(),
    };
    anyhow!("{flag}: {message}")
}

// The defaults quoted in the help text are the library's.
const _: () = assert!(DEFAULT_LENGTH_SIGMA_MM == 0.4);
const _: () = assert!(DEFAULT_TWIST_SIGMA_DEG == 0.07);
const _: () = assert!(DEFAULT_ZERO_SIGMA_DEG == 0.45);

/// `LOW:HIGH` of --temperature, °C.
fn temperature_range(s: &str) -> Result<[f64; 2], String> {
    let (lo, hi) = s
        .split_once(':')
        .ok_or_else(|| format!("{}: give LOW:HIGH in °C, e.g. 15:30", quoted(s)))?;
    let number = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| (-100.0..=200.0).contains(v))
            .ok_or_else(|| format!("{} is not a temperature in °C (−100 to 200)", quoted(t)))
    };
    let (lo, hi) = (number(lo)?, number(hi)?);
    if lo > hi {
        return Err(format!("{}: LOW above HIGH", quoted(s)));
    }
    Ok([lo, hi])
}

/// `X,Y,Z` of --drift, mm/h.
fn drift_vector(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("{}: give X,Y,Z in mm/h, e.g. 0.1,0,-0.05", quoted(s)))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("{}: three numbers X,Y,Z in mm/h", quoted(s)))
}
