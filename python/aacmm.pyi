"""The aacmm toolkit: forward kinematics, metrics, identifiability, simulation
and calibration of D-H arms (articulated-arm CMMs).

Lengths in mm; angles in rad unless an argument says otherwise. Arrays are
numpy float64. Parameters are in the order ``a1..an, d1..dn, alpha1..alphan,
theta1..thetan, Bx, By, Bz`` (see :func:`param_names`).
"""

import os
import pathlib
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_AngleUnit = Literal["rad", "deg"]
_Readings = npt.ArrayLike
_Length = Tuple[str, str, float, Optional[float]]
_Array = npt.NDArray[np.float64]
_Names = Union[str, Sequence[Any]]

class _Positions(TypedDict):
    """Reference positions as ``DataSet.positions`` gives them: the arguments
    of :meth:`DataSet.from_positions` (angles in rad)."""

    labels: List[str]
    frames: List[str]
    q: _Array
    xyz: _Array
    uncertainty: _Array

class _Tool(TypedDict):
    offset_mm: _Array
    sigma_mm: Optional[_Array]

class _Frame(TypedDict):
    """A frame fitted with the arm: ``y = R p + t`` maps the arm's base
    coordinates into the instrument's."""

    rotation_deg: _Array
    translation_mm: _Array
    small_rotation_sigma_deg: Optional[_Array]
    """σ (k = 1) of small rotations about the instrument's x, y, z axes, deg."""
    translation_sigma_mm: Optional[_Array]
    rotation_matrix: _Array

class _Auxiliary(TypedDict):
    """An auxiliary column fitted with the arm (a correction beyond geometry,
    a frame's coordinate), in its ``unit``."""

    unit: str
    start: float
    calibrated: float
    sigma: Optional[float]
    sigma_of: Optional[str]
    fixed: Optional[str]

class _Region(TypedDict):
    """One band of distance from the shoulder of an uncertainty map."""

    reach_from_mm: float
    reach_to_mm: float
    poses: int
    rms_mm: float
    max_mm: float

class _MapPoints(TypedDict):
    """An uncertainty map's even sample of its poses, one entry per pose."""

    reach_mm: _Array
    height_mm: _Array
    radius_mm: _Array

class _UncertaintyMap(TypedDict):
    """The predicted position uncertainty over a sampled workspace: the
    radius that holds the calibrated probe position's error with
    ``coverage`` (95 %) probability, ``k_isotropic`` (2.80) σ for an
    isotropic 3-D error."""

    coverage: float
    k_isotropic: float
    workspace: str
    poses: int
    rms_mm: float
    median_mm: float
    max_mm: float
    regions: List[_Region]
    points: _MapPoints
    # In Calibration.uncertainty_maps_in_frames and _at_tools only: the
    # frame or tool point the radii are in or at.
    frame: str
    tool: str

class AacmmError(Exception):
    """Base class of the errors aacmm raises (besides OSError for unreadable
    files and ValueError/TypeError for malformed arguments)."""

class InputError(AacmmError):
    """Invalid input data: a file's content (the message names file, line and
    field) or arrays (the message names ``<arrays>``, the 1-based touch or
    length, and the field)."""

class CalibrationError(AacmmError):
    """The calibration (or identification, evaluation, simulation) cannot run
    on this input."""

class UnsupportedError(AacmmError):
    """An arm with a joint count the toolkit has no kernel for (it computes 1 to 12)."""

def param_names(joints: int) -> List[str]:
    """The names of the ``4·joints + 3`` parameters, in the toolkit's order.
    A joint count without a kernel (not 1 to 12) raises :class:`UnsupportedError`."""

class Arm:
    """An arm: its D-H geometry (mm, rad) prepared for the generated kernel of
    its chain (1 to 12 joints, revolute or prismatic: ``joint_types``). Immutable; safe to share between threads."""

    @staticmethod
    def from_file(path: _Path, accept_rejected: bool = False) -> "Arm":
        """Reads an arm file (TOML). Errors name the file, line and field
        (InputError; OSError when it cannot be read); warnings go to
        ``warnings`` and are issued as UserWarning. A file whose
        ``[verdict]`` says NOT usable (a refused calibration's
        ``calibrated.toml``) is refused unless ``accept_rejected=True``: it
        is then read with a warning. A path ``-`` is a file of that name
        (not standard input, as on the command line)."""
    @staticmethod
    def from_params(
        joints: int, params: npt.ArrayLike, name: str = "arm", joint_types: Optional[str] = None
    ) -> "Arm":
        """An arm from its ``4·joints + 3`` parameters (mm, rad), no joint limits.
        ``joint_types`` (default all revolute): one letter per joint from the
        base, ``R`` revolute, ``P`` prismatic (its reading, mm, adds to ``d``)."""
    @property
    def name(self) -> str: ...
    @property
    def joints(self) -> int: ...
    @property
    def joint_types(self) -> str:
        """Each joint's kind from the base: ``R`` revolute, ``P`` prismatic
        (its readings are mm whatever the angle unit), e.g. ``"PRRRRRR"``."""
    @property
    def source(self) -> str:
        """The file as named, ``<parameters>``, ``<calibration>`` or ``<simulation>``."""
    @property
    def warnings(self) -> List[str]: ...
    @property
    def params(self) -> _Array:
        """The parameters (mm, rad), a new array of ``4·joints + 3``."""
    @property
    def param_names(self) -> List[str]: ...
    @property
    def limits(self) -> List[Optional[Tuple[float, float]]]:
        """Per joint, ``(min, max)`` rad, or None."""
    def positions(self, q: _Readings, angle_unit: _AngleUnit = "rad") -> _Array:
        """Probe positions (mm): ``q`` n × joints → n × 3 (a 1-D ``q`` of one
        pose gives shape (3,)). Bit-identical to the Rust API. Runs without
        the GIL. An output too large to allocate is a MemoryError before any
        work (as for :meth:`jacobians`, :meth:`joint_jacobian` and the copy
        of ``q`` a :class:`DataSet` keeps)."""
    def jacobians(
        self, q: _Readings, angle_unit: _AngleUnit = "rad"
    ) -> Tuple[_Array, _Array]:
        """``(p, jac)``: positions n × 3 and parameter Jacobians
        n × 3 × (4·joints + 3), ``jac[i, k, c] = ∂p_k/∂param_c`` (mm/mm,
        mm/rad)."""
    def joint_jacobian(
        self, q: _Readings, angle_unit: _AngleUnit = "rad"
    ) -> Tuple[_Array, _Array]:
        """``(p, jac)``: positions n × 3 and joint Jacobians n × 3 × joints,
        ``jac[i, k, j] = ∂p_k/∂q_j`` (mm/rad)."""
    def to_toml(self, length_unit: str = "mm", angle_unit: str = "deg") -> str:
        """The arm in the arm-file schema."""
    def to_dict(self) -> Dict[str, float]:
        """Parameter name → value (mm, rad)."""

class DataSet:
    """Touches grouped by point (order of first appearance), with reference
    lengths between points, and reference positions an instrument saw (each
    frame's registration fitted with the arm). Immutable."""

    def __init__(
        self,
        labels: Sequence[Any],
        q: _Readings,
        lengths: Optional[Sequence[Union[Tuple[Any, Any, float], Tuple[Any, Any, float, Optional[float]]]]] = None,
        angle_unit: _AngleUnit = "rad",
        joint_types: Optional[str] = None,
    ) -> None:
        """Touches from arrays: ``labels`` (one per touch, taken as str), ``q``
        n × joints readings (a prismatic joint's of ``joint_types``, e.g.
        ``"PRRRRRR"``, in mm whatever ``angle_unit`` says), ``lengths`` ``(point_a, point_b, distance_mm[,
        uncertainty_mm])``. Checked by the library as files are (InputError
        naming ``<arrays>``, the 1-based touch or length, and the field)."""
    @staticmethod
    def from_files(
        poses: Optional[_Path] = None,
        lengths: Optional[_Path] = None,
        angle_unit: _AngleUnit = "deg",
        joints: Optional[int] = None,
        positions: Optional[_Path] = None,
        joint_types: Optional[str] = None,
    ) -> "DataSet":
        """Reads a poses file (CSV ``point,q1,...,qn``, degrees by default; the
        columns of the prismatic joints of ``joint_types``, e.g. ``"PRRRRRR"``,
        mm whatever ``angle_unit`` says),
        optionally a reference-lengths file (CSV
        ``point_a,point_b,distance[,uncertainty]``, mm) and a
        reference-positions file (CSV
        ``point,q1,...,qn,x,y,z[,frame][,uncertainty]``, mm: the command
        line's ``--positions``), or the positions file alone
        (``poses=None``). A path ``-`` is a file of that name (not standard
        input, as on the command line)."""
    @staticmethod
    def from_positions(
        q: _Readings,
        xyz: npt.ArrayLike,
        frames: Optional[_Names] = None,
        uncertainty: Optional[npt.ArrayLike] = None,
        labels: Optional[Sequence[Any]] = None,
        angle_unit: _AngleUnit = "rad",
        joint_types: Optional[str] = None,
        tools: Optional[_Names] = None,
    ) -> "DataSet":
        """Reference positions alone, from arrays: ``q`` n × joints readings
        (``joint_types`` ``"PRRRRRR"``: a slide's column in mm whatever
        ``angle_unit`` says),
        ``xyz`` n × 3 where the instrument saw the probe (mm, its frame),
        ``frames`` per row its frame (a str for every row; default
        ``"instrument"``), each with its own fitted registration,
        ``uncertainty`` σ per coordinate (mm; one number or one per row; NaN:
        not stated), ``labels`` per row its point (default ``P1``, ``P2``,
        …), ``tools`` per row the tool point seen (a ``[[tool]]`` of the arm
        file, its offset fitted with the arm; ``""`` the arm's ``[probe]``;
        a str for every row). ValueError naming the argument and row (0-based) for a wrong
        shape, a non-finite value, an uncertainty ≤ 0, an empty name, or a
        frame with fewer than 3 distinct positions or all on one line."""
    def with_positions(
        self,
        q: _Readings,
        xyz: npt.ArrayLike,
        frames: Optional[_Names] = None,
        uncertainty: Optional[npt.ArrayLike] = None,
        labels: Optional[Sequence[Any]] = None,
        angle_unit: _AngleUnit = "rad",
        tools: Optional[_Names] = None,
    ) -> "DataSet":
        """These touches with reference positions from arrays (as
        :meth:`from_positions`, ``q`` with this data set's joints, a slide's
        column in mm as this data set's joint types say), fitted
        together: a new data set. ValueError if this one has positions
        already."""
    def __len__(self) -> int:
        """Number of touches (0 for reference positions alone)."""
    @property
    def joints(self) -> int: ...
    @property
    def points(self) -> List[str]: ...
    @property
    def labels(self) -> List[str]:
        """Per touch, in the data set's order (grouped by point)."""
    @property
    def q(self) -> _Array:
        """Readings (rad), n × joints, in the data set's order."""
    @property
    def lengths(self) -> List[_Length]: ...
    @property
    def poses_file(self) -> str: ...
    @property
    def lengths_file(self) -> Optional[str]: ...
    @property
    def positions_file(self) -> Optional[str]:
        """The positions file as named (``<arrays>``), or None without
        reference positions."""
    @property
    def positions(self) -> Optional[_Positions]:
        """The reference positions (None without), in the rows' order."""
    @property
    def warnings(self) -> List[str]: ...
    def source_of(self, i: int) -> str:
        """``file:line`` of touch ``i`` (data set order)."""

class Noise:
    """What is known of the measurement noise (the command line's noise
    options): σ of each encoder reading (degrees), of the probe seating (mm),
    of a reference length that states none (mm), a weight of every
    reference length (1/mm; 0 or None: from the uncertainties), and the σ
    per coordinate of a reference position that states none, ``position_mm
    + position_mm_per_m · distance`` (mm, mm per metre from the instrument;
    a laser tracker's 0.015 and 0.006), and the σ per axis of a tool
    orientation a positions file gives (``qw,qx,qy,qz``), degrees
    (``orientation_deg``; a file with orientations needs it). Checked by the
    library when made:
    ValueError naming the argument (``encoder_deg`` at most 180). Noise so
    large or small that its weights overflow or vanish on the data is a
    ValueError in :func:`identify` and :func:`calibrate` alike."""

    def __init__(
        self,
        encoder_deg: Optional[float] = None,
        probe_mm: Optional[float] = None,
        length_default_mm: float = 0.001,
        length_weight: Optional[float] = None,
        position_mm: Optional[float] = None,
        position_mm_per_m: Optional[float] = None,
        orientation_deg: Optional[float] = None,
    ) -> None: ...
    @property
    def encoder_deg(self) -> Optional[float]: ...
    @property
    def probe_mm(self) -> Optional[float]: ...
    @property
    def length_default_mm(self) -> float: ...
    @property
    def length_weight(self) -> Optional[float]: ...
    @property
    def position_mm(self) -> Optional[float]: ...
    @property
    def position_mm_per_m(self) -> Optional[float]: ...
    @property
    def orientation_deg(self) -> Optional[float]: ...
    @property
    def stated(self) -> bool:
        """Whether any touch noise is stated."""

def evaluate(arm: Arm, data: DataSet) -> Dict[str, Any]:
    """The figures of ``arm`` on ``data`` (``aacmm evaluate``'s ``evaluation``), mm:
    touches and lengths only (reference positions alone: ValueError; their
    figures are a calibration's ``summary``)."""

def identify(
    arm: Arm, data: DataSet, noise: Optional[Noise] = None, threads: Optional[int] = None
) -> Dict[str, Any]:
    """What the data can determine (``aacmm identify``'s ``identification``)."""

class Campaign:
    """A simulated campaign with a known true arm."""

    @property
    def nominal(self) -> Arm: ...
    @property
    def true_arm(self) -> Arm: ...
    @property
    def labels(self) -> List[str]:
        """Per touch (row of poses.csv), the socket's label."""
    @property
    def q(self) -> _Array:
        """Encoder readings (rad), n × joints, rows of poses.csv."""
    @property
    def socket_labels(self) -> List[str]: ...
    @property
    def sockets(self) -> _Array:
        """True socket centres, mm, k × 3."""
    @property
    def lengths(self) -> List[_Length]: ...
    @property
    def data(self) -> DataSet: ...
    def write(self, dir: _Path, *, force: bool = False) -> List[pathlib.Path]:
        """Writes poses.csv, lengths.csv, sockets.csv, true_arm.toml,
        campaign.toml (the bytes of ``aacmm simulate``), each whole or not at
        all. OSError when ``dir`` holds results of an earlier run (a
        campaign's, a calibration's, a report's) and not ``force``;
        ValueError for an empty path."""

def simulate(
    arm: Arm,
    *,
    poses: int,
    seed: int,
    sockets: Optional[int] = None,
    sockets_file: Optional[_Path] = None,
    errors: Literal["paper", "random", "assembled"] = "paper",
    true_arm: Optional[Arm] = None,
    error_scale: Optional[float] = None,
    encoder_noise_deg: float = 0.0,
    probe_noise_mm: float = 0.0,
    reference_lengths: Optional[int] = None,
    length_uncertainty_mm: Optional[float] = None,
) -> Campaign:
    """Simulates a calibration campaign (``aacmm simulate``). A setting out
    of range is a ValueError naming the argument (``poses``, ``seed``,
    ``encoder_noise_deg``, …), as in :func:`calibrate`; a campaign the arm
    cannot perform (sockets out of reach) is a CalibrationError. ``seed``
    is at most 2**63 − 1 (written to ``campaign.toml``), as in
    :func:`calibrate`; ``encoder_noise_deg`` at most 180, as
    ``Noise(encoder_deg=...)``."""

class VerdictEntry:
    """One reason (or note) of a :class:`Verdict`."""

    @property
    def kind(self) -> str:
        """A short stable name of what it says: ``"chi_square"``,
        ``"outliers"``, ``"unconfirmed"``, ``"data_disagree_with_arm"``,
        ``"not_nominal_geometry"``, ``"undetermined"``, … (new kinds may be
        added)."""
    @property
    def data(self) -> Dict[str, Any]:
        """Its figures (the χ² test, the outliers' ``file:line``, the
        parameters and their moves, the search's starts, …)."""
    @property
    def text(self) -> str:
        """The sentence, its remedy naming this module's arguments
        (``robust="huber"``, ``accept_poor_fit=True``), never a flag."""

class Verdict:
    """Whether a calibration may be used, and why not, typed."""

    @property
    def usable(self) -> bool:
        """The calibration may be used (``Calibration.successful``)."""
    @property
    def reasons(self) -> List[VerdictEntry]:
        """Why not, the first cause first (empty when usable)."""
    @property
    def notes(self) -> List[VerdictEntry]:
        """What to know although it may be used."""

class Calibration:
    """The result of :func:`calibrate`."""

    @property
    def arm(self) -> Arm:
        """The calibrated arm."""
    @property
    def params(self) -> _Array:
        """Calibrated parameters (mm, rad)."""
    @property
    def sigma(self) -> _Array:
        """Standard uncertainties (mm, rad); NaN for fixed parameters."""
    @property
    def fixed(self) -> Dict[str, str]:
        """Fixed parameter → reason."""
    @property
    def free(self) -> List[str]:
        """The free parameters: rows and columns of ``correlation``."""
    @property
    def correlation(self) -> _Array:
        """Correlation matrix of the free parameters."""
    @property
    def frames(self) -> Dict[str, _Frame]:
        """Each instrument frame fitted with the arm (empty without reference
        positions): rotation vector (deg) and translation (mm) of ``y = R p +
        t``, their σ (k = 1; None where not determined) as calibrated.toml's
        ``[[frame]]`` tables, and ``R`` (3 × 3)."""
    @property
    def tools(self) -> Dict[str, _Tool]:
        """Each tool point fitted with the arm (a ``[[tool]]`` of the arm
        file that rows named; empty when none did): ``offset_mm`` (x, y, z
        in the last joint's frame) and ``sigma_mm`` (k = 1; None where not
        determined), as calibrated.toml's ``[[tool]]`` tables."""
    @property
    def auxiliary(self) -> Dict[str, _Auxiliary]:
        """Each auxiliary column, in the report's order: the corrections
        beyond geometry (``compliance2`` µrad/(N·m), ``harmonic2.sin1`` and
        ``harmonic2.cos1`` deg, ``thermal.cte`` ppm/K, ``drift.x`` … mm/h),
        then each frame's ``NAME.rx`` … ``NAME.tz`` (deg, mm): name →
        ``unit``, ``start``, ``calibrated``, ``sigma`` (k = 1; None where
        not determined) and ``fixed`` (why it was held — a correction these
        data cannot separate — or None)."""
    @property
    def physics(self) -> Optional[Dict[str, Any]]:
        """The arm's physics at the fit (None when no correction is stated or
        fitted — masses alone correct nothing): ``link_masses``, ``probe_mass``, ``gravity``, and
        the corrections fitted or as stated — ``compliance`` per joint
        (rad/(N·m)), ``harmonics`` (rad), ``backlash`` per joint (rad, mm
        for a slide; absent when none), ``cte_per_k`` (1/K),
        ``reference_temperature_c`` — as ``report["calibration"]["physics"]``;
        ``drift_mm_per_h`` when a drift was fitted."""
    @property
    def uncertainty_map(self) -> Optional[_UncertaintyMap]:
        """The predicted position uncertainty over a sampled workspace, as
        ``report["uncertainty_map"]`` (None when the covariance is not
        finite): ``coverage``, ``k_isotropic`` (2.80: the 95 % radius of an
        isotropic 3-D error in σ, not 2), ``workspace``, ``poses``,
        ``rms_mm``, ``median_mm``, ``max_mm`` of the 95 % radius,
        ``regions`` per band of distance from the shoulder, and ``points``
        (the figure's sample) as arrays ``reach_mm``, ``height_mm``,
        ``radius_mm``."""
    @property
    def uncertainty_maps_in_frames(self) -> List[_UncertaintyMap]:
        """The map in each instrument frame fitted (``frame`` its name; the
        radii include the frame's registration), as
        ``report["uncertainty_maps_in_frames"]``."""
    @property
    def uncertainty_maps_at_tools(self) -> List[_UncertaintyMap]:
        """The map at each tool point whose offset was fitted (``tool`` its
        name; the radii include the offset's uncertainty), as
        ``report["uncertainty_maps_at_tools"]``."""
    @property
    def successful(self) -> bool:
        """Whether the calibration is usable: the verdict
        (``report["verdict"]["usable"]``, exit 0 of ``aacmm calibrate``) —
        a confirmed minimum, the nominal's kind of geometry, and (unless
        ``accept_poor_fit``) a χ² and fitted data that agree."""
    @property
    def verdict(self) -> Verdict:
        """The verdict, typed: each reason and note with its ``kind``, its
        ``data`` and its ``text`` in Python's words; ``report["verdict"]``
        has the command line's sentences."""
    @property
    def summary(self) -> Dict[str, Any]:
        """``successful`` (the verdict, as the property), method, why it
        stopped (``stop``, and ``stop_text`` in words), ``converged`` (the
        solver's own criterion, which a refused calibration may meet),
        iterations, dof, σ0, touch σ, costs, and the before/after figures
        (fitted, held out, cross-validation folds); with reference positions
        each figure's ``positions`` holds the 3-D errors (``count``,
        ``mean``, ``rms``, ``max``, mm)."""
    @property
    def report(self) -> Dict[str, Any]:
        """Everything calibration.json holds (mm and degrees)."""
    def to_json(self) -> str:
        """The text of ``aacmm calibrate``'s calibration.json, final newline
        included."""
    def text(self) -> str:
        """The summary ``aacmm calibrate`` prints."""
    def write(self, dir: _Path, *, force: bool = False) -> List[pathlib.Path]:
        """Writes the files of ``aacmm calibrate --out dir`` (created if
        missing): calibrated.toml, calibration.json, timing.json, report.html
        and its SVG figures, each whole or not at all; returns their paths.
        OSError when one cannot be written, or when ``dir`` holds results of
        an earlier run (a calibration's, a campaign's, a report's) and not
        ``force``; ValueError for an empty path."""

#: Points probed on reference spheres: a sphere-surface file's path (CSV
#: ``sphere,q1,…,qn[,articulation]``, as ``--spheres``), or a pair
#: ``(labels, q)`` — per point its sphere's label and its readings,
#: ``n × joints``, in rad (mm for a slide) — or a triple ``(labels, q,
#: tools)``, ``tools`` per point the probe (a ``[[tool]]`` of the arm file;
#: ``""`` its ``[probe]``) or one str for every point, one probe a sphere.
SpherePoints = Union[
    str,
    "os.PathLike[str]",
    Tuple[Sequence[str], npt.ArrayLike],
    Tuple[Sequence[str], npt.ArrayLike, _Names],
]

def calibrate(
    arm: Arm,
    data: Optional[DataSet] = None,
    *,
    method: Literal["global", "lm", "sa", "hybrid"] = "global",
    fix: Union[str, Sequence[str], None] = None,
    noise: Optional[Noise] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    cross_validate: Optional[int] = None,
    validate: Optional[DataSet] = None,
    robust: Optional[Literal["huber", "cauchy"]] = None,
    robust_scale: Optional[float] = None,
    prior: Optional[str] = None,
    accept_poor_fit: bool = False,
    compliance: Optional[str] = None,
    harmonics: Optional[str] = None,
    thermal: bool = False,
    drift: bool = False,
    backlash: Optional[str] = None,
    register_held_out: bool = False,
    spheres: Optional[SpherePoints] = None,
    sphere_diameter: Optional[float] = None,
    validate_spheres: Optional[SpherePoints] = None,
    sphere_angle_unit: Literal["deg", "rad"] = "deg",
    global_starts: Optional[int] = None,
) -> Calibration:
    """Calibrates ``arm`` on ``data``: the library's session, as ``aacmm
    calibrate`` runs it; the report is the command line's bit for bit.
    ``fix`` defaults to ``"auto"``. ``robust`` (``"huber"`` or
    ``"cauchy"``) refits with per-touch weights (``--robust``; the weights
    in ``report["calibration"]["robust"]``), ``robust_scale`` its tuning
    constant. ``prior`` states tolerances as ``--prior`` does
    (``"length=0.5mm,angle=0.1deg"``, over the arm file's ``[prior]``;
    ``"none"`` ignores the file's). ``validate`` is a held-out data set of
    touches, reference positions or both (positions in a fitted frame are
    scored in it; a frame the fit does not have is a CalibrationError naming
    the fitted frames, unless ``register_held_out``, which registers it on
    its own positions — optimistic — and says so in
    ``report["validation"]["held_out"]["registered_on_itself"]``, as
    ``--register-held-out``). ``accept_poor_fit`` calls a poor χ² or a
    fit worse than nominal usable (never a wrong geometry). Models beyond
    geometry, fitted with the arm as the command line's flags:
    ``compliance`` (``"2,3"``, joints from 1, loaded by the arm file's
    masses: ``--compliance``), ``harmonics`` (``"2:1,5:1-2"``,
    ``JOINT:ORDERS``: ``--harmonics``), ``backlash`` (``"2,3"``, joints from
    1, the half-play on the flank the arm file's masses press:
    ``--backlash``), ``thermal`` (against the data's
    ``temperature`` column: ``--thermal``), ``drift`` (against its ``time``
    column: ``--drift``); their values in :attr:`Calibration.auxiliary` and
    :attr:`Calibration.physics`. Readings outside
    the arm's joint limits are a UserWarning (and in the report's
    warnings). ``seed`` is at most 2**63 − 1, as in :func:`simulate`;
    ``threads`` 1 to 1024, as in :func:`identify` (and ``--threads``).
    ``spheres`` adds points probed on reference spheres (``--spheres``;
    ``data`` may then be left out), ``sphere_diameter`` their stated
    diameter in mm (``--sphere-diameter``: fixes the scale; needs the arm
    file's ``[probe] ball_diameter_mm``), ``validate_spheres`` held-out
    points on spheres (``--validate-spheres``: each sphere refitted on its
    points with the arm fixed, in ``report["validation"]["held_out_spheres"]``);
    a file's readings are in ``sphere_angle_unit``; with ``cross_validate``
    each sphere's points are dealt to the folds
    (``report["validation"]["cross_validation"]["folds"][i]["terms"]``).
    ``global_starts`` is the global search's most random starts
    (``--global-starts``, default 100; at least 1).
    ValueError for a bad option (naming the argument),
    CalibrationError when the data cannot determine the free parameters; a
    calibration that is not usable is returned: check ``successful`` and
    ``verdict``."""

def qualify_probe(
    arm: Arm,
    spheres: Union[_Path, Tuple[Sequence[str], _Readings], Tuple[Sequence[str], _Readings, Union[str, Sequence[str]]]],
    sphere_diameter_mm: float,
    *,
    tool: str = "probe",
    noise: Optional[Noise] = None,
    tolerance_mm: float = 0.05,
    max_form_mm: Optional[float] = None,
    angle_unit: _AngleUnit = "deg",
) -> Tuple[Dict[str, Any], Optional[Arm]]:
    """Qualifies the probe ``tool`` (``"probe"``, the arm's ``[probe]``, or a
    ``[[tool]]``'s name) on points touched on one reference sphere of
    certified diameter ``sphere_diameter_mm``, the arm's geometry held
    (``aacmm probe``): its tip offset and effective ball diameter with their
    σ, the sphere's form as the probe sees it. ``spheres`` is a
    sphere-surface file's path (readings in ``angle_unit``) or ``(labels,
    q[, tools])`` arrays (rad); other probes' rows are left out. Returns the
    qualification (``usable``; ``refusals`` why not, in this module's words;
    ``warnings``; ``offset``, ``offset_sigma``, ``ball_diameter_mm``,
    ``ball_sigma_mm``, ``moved_mm``) and the arm with the qualified probe, or
    ``None`` when it may not be used. ValueError or InputError for a probe
    the arm does not know, a sphere diameter out of range, rows on more than
    one sphere."""
