"""The scenario schema: every table a scenario TOML may hold and every key of each, with its
type, default and meaning — the one list the validators check keys against
(:func:`navfdi._fields._check_keys` takes a section name of :data:`SECTIONS`) and the
scenario reference in the documentation is generated from
(``docs/scripts/scenario_reference.py`` → ``docs/reference/scenario.md``).

Types: *length*, *angle*, *time*, … are quantity strings with a unit (``"0.5 m"``,
``"2 deg"``); ``×3`` one value or three (x, y, z / east, north, up); *name* a string of
letters, digits, ``_`` and ``-``; *probability* a number in (0, 1). Frames: *body* is
forward-right-down, *IMU* the IMU's own axes, *ENU* east-north-up.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Key", "Section", "SECTIONS", "keys"]


@dataclass(frozen=True)
class Key:
    """One key of a section: ``type`` (with its unit or allowed values), ``default``
    (``"required"`` when it must be given, ``"—"`` when absent means not used) and
    ``meaning``."""

    type: str
    default: str
    meaning: str


@dataclass(frozen=True)
class Section:
    """A table of the scenario: ``title`` (how it is written in TOML), ``what`` it is for,
    and its ``keys`` by name."""

    title: str
    what: str
    keys: dict[str, Key]


def _s(title: str, what: str, rows: list[tuple[str, str, str, str]]) -> Section:
    return Section(title, what, {k: Key(t, d, m) for k, t, d, m in rows})


REQ = "required"

_DETECTOR_KINDS = "chi2, sprt, joint, state_chi2"

SECTIONS: dict[str, Section] = {
    "": _s("top level", "The scenario file's top-level keys.", [
        ("name", "string", REQ, "scenario name (outputs and reports)"),
        ("description", "string", "—", "one line shown by `navfdi scenarios`"),
        ("duration", "time", "required (recorded logs: from the GNSS log)", "run length from time 0"),
        ("dt", "time", "required (recorded logs: from the GNSS log)", "filter and record epoch interval"),
        ("architecture", "federated, centralized, tight, ultra_tight, loosely_coupled", "federated", "the filter architecture; its table of the same name configures it"),
        ("trajectory", "table", "required (simulation)", "the simulated vehicle's motion"),
        ("ins", "table", "required (simulation)", "the simulated INS's error model"),
        ("sensors", "list of tables", REQ, "the aiding sensors (`[[sensors]]`)"),
        ("faults", "list of tables", "none", "faults injected into sensor measurements (`[[faults]]`)"),
        ("federated", "table", "—", "federated filter settings (architecture federated)"),
        ("centralized", "table", "—", "centralized filter settings (architecture centralized)"),
        ("tight", "table", "—", "tightly coupled filter settings (architecture tight)"),
        ("ultra_tight", "table", "—", "vector-tracking settings (architecture ultra_tight)"),
        ("loosely_coupled", "table", "—", "strapdown INS with GNSS solutions (architecture loosely_coupled, recorded logs)"),
        ("source", "table", "—", "recorded logs to run on instead of a simulation"),
        ("terrain", "table", "—", "terrain under the vehicle (radio altimeter)"),
        ("state_chi2", "table", "—", "state chi-square test of the navigation solution"),
        ("modes", "table", "—", "paper 003's navigation modes by distance to a target"),
        ("variants", "list of tables", "none", "configurations compared on identical measurements (`[[variants]]`)"),
    ]),
    "trajectory": _s("[trajectory] (segments)", "The simulated motion as segments from a start point.", [
        ("latitude", "angle", REQ, "start latitude"),
        ("longitude", "angle", REQ, "start longitude"),
        ("height", "length", REQ, "start height above the ellipsoid"),
        ("heading", "angle", "0 deg", "start heading from north"),
        ("speed", "velocity", "0 m/s", "start ground speed"),
        ("segments", "list of tables", REQ, "the motion, in order (`[[trajectory.segments]]`; the last is held to the end)"),
    ]),
    "trajectory_waypoints": _s("[trajectory] (waypoints)", "The simulated motion flown through waypoints (given instead of segments).", [
        ("latitude", "angle", REQ, "reference point latitude (the waypoints' origin)"),
        ("longitude", "angle", REQ, "reference point longitude"),
        ("height", "length", REQ, "reference point height above the ellipsoid"),
        ("waypoints", "list of [east, north, up] lengths", REQ, "points flown through, ENU from the reference point (at least two)"),
        ("speed", "velocity", REQ, "ground speed (> 0)"),
        ("turn_rate", "angular rate", "30 deg/s", "rate of the coordinated turns centred on the waypoints"),
    ]),
    "segment.stationary": _s("[[trajectory.segments]] kind = \"stationary\"", "At rest.", [
        ("kind", "stationary", REQ, "segment kind"), ("duration", "time", REQ, "length")]),
    "segment.accelerate": _s("[[trajectory.segments]] kind = \"accelerate\"", "Straight, level, changing speed.", [
        ("kind", "accelerate", REQ, "segment kind"), ("duration", "time", REQ, "length"),
        ("acceleration", "acceleration", REQ, "along-track acceleration (negative brakes)")]),
    "segment.climb": _s("[[trajectory.segments]] kind = \"climb\"", "Straight at constant speed, climbing.", [
        ("kind", "climb", REQ, "segment kind"), ("duration", "time", REQ, "length"), ("rate", "velocity", REQ, "vertical speed")]),
    "segment.level": _s("[[trajectory.segments]] kind = \"level\"", "Straight and level at constant speed.", [
        ("kind", "level", REQ, "segment kind"), ("duration", "time", REQ, "length")]),
    "segment.turn": _s("[[trajectory.segments]] kind = \"turn\"", "Level coordinated turn at constant speed.", [
        ("kind", "turn", REQ, "segment kind"), ("duration", "time", REQ, "length"), ("rate", "angular rate", REQ, "turn rate (positive right)")]),
    "segment.descent": _s("[[trajectory.segments]] kind = \"descent\"", "Straight at constant speed, descending.", [
        ("kind", "descent", REQ, "segment kind"), ("duration", "time", REQ, "length"), ("rate", "velocity", REQ, "vertical speed (positive down)")]),
    "ins": _s("[ins]", "The simulated INS's errors (15-state error model).", [
        ("gyro_bias", "angular rate", REQ, "constant gyro bias σ"),
        ("gyro_white", "angular rate", REQ, "gyro white noise σ per sample"),
        ("gyro_markov", "angular rate", REQ, "gyro first-order Gauss-Markov σ"),
        ("gyro_tau", "time", REQ, "its correlation time"),
        ("accel_markov", "acceleration", REQ, "accelerometer Gauss-Markov σ"),
        ("accel_tau", "time", REQ, "its correlation time"),
        ("init_level", "angle", REQ, "initial level attitude error σ"),
        ("init_heading", "angle", REQ, "initial heading error σ"),
        ("init_velocity", "velocity", REQ, "initial velocity error σ"),
        ("init_position", "length", REQ, "initial position error σ"),
    ]),
    "terrain": _s("[terrain]", "Terrain height under the vehicle, a sum of waves (radio altimeter).", [
        ("waves", "list of tables", REQ, "the waves (`[[terrain.waves]]`)")]),
    "terrain.waves": _s("[[terrain.waves]]", "One terrain wave.", [
        ("amplitude", "length", REQ, "height amplitude"),
        ("wavelength", "length", REQ, "horizontal wavelength"),
        ("heading", "angle", "0 deg", "direction the wave travels along"),
        ("phase", "angle", "0 deg", "phase at the start point"),
    ]),
    "sensors": _s("[[sensors]]", "An aiding sensor: what it measures, its noise and rate.", [
        ("name", "name", REQ, "unique name the other tables refer to"),
        ("kind", "cns, gnss, gnss_position, gnss_velocity, baro, vision, gnss_ranges, radio_altimeter", REQ, "what it measures (its components: cns phi_e/n/u; gnss pos_e/n/u, vel_e/n/u; baro and radio_altimeter h; gnss_ranges pseudorange, rate)"),
        ("noise", "one quantity or one per component", REQ, "white noise σ per component (> 0; gnss_ranges: pseudorange and rate σ at zenith)"),
        ("bias", "one quantity or one per component", "none", "constant bias σ per component (simulation)"),
        ("proportional_noise", "fraction", "—", "radio altimeter: noise σ as a share of the height above the terrain"),
        ("rate", "frequency", REQ, "measurement rate"),
        ("outages", "list of [start, end] times", "none", "windows without measurements"),
        ("ranges", "table", "required (gnss_ranges)", "the satellites' settings"),
    ]),
    "sensors.ranges": _s("[sensors.ranges]", "A gnss_ranges sensor's satellites and receiver clock.", [
        ("systems", "list of gps, galileo", "[\"gps\"]", "constellations used"),
        ("elevation_mask", "angle", REQ, "satellites below it are not used"),
        ("elevation_noise", "bool", "false", "σ grows as 1/sin(elevation) (and with C/N0 when cn0_reference is set)"),
        ("epoch", "time", "0 s", "simulation: the constellation's time at the run's start"),
        ("clock", "table", REQ, "receiver clock model"),
        ("cn0_reference", "carrier to noise (dB-Hz)", "—", "C/N0 at which the σ is the one given (recorded logs: scaled by the recorded C/N0)"),
        ("correlated", "table", "—", "simulation: time-correlated pseudorange errors"),
    ]),
    "sensors.ranges.correlated": _s("[sensors.ranges.correlated]", "Simulation: a share of each pseudorange error drawn as a first-order Gauss-Markov process per satellite.", [
        ("fraction", "number in [0, 1)", REQ, "share of each pseudorange's variance (σ by elevation, squared) that is correlated; the rest stays white"),
        ("tau", "time (s)", REQ, "correlation time"),
    ]),
    "sensors.ranges.clock": _s("[sensors.ranges.clock]", "Receiver clock: initial σ and random-walk densities.", [
        ("bias", "length", REQ, "initial clock bias σ"),
        ("drift", "velocity", REQ, "initial clock drift σ"),
        ("bias_psd", "m²/s", REQ, "bias random-walk density"),
        ("drift_psd", "m²/s³", REQ, "drift random-walk density"),
    ]),
    "faults": _s("[[faults]]", "A fault added to a sensor's measurements (simulated or recorded).", [
        ("id", "name", REQ, "unique name (tables, events)"),
        ("sensor", "name", REQ, "the sensor it corrupts"),
        ("components", "list of component names, or \"all\"", REQ, "which components"),
        ("kind", "step, ramp, quadratic", REQ, "shape"),
        ("magnitude", "quantity (per s for ramp, per s² for quadratic) or multiple of σ (\"3 sigma\")", REQ, "size per component"),
        ("start", "time, or GPS time (\"WEEK:SOW\", ISO GPST/UTC)", REQ, "onset (s from time 0, or GPS time on recorded logs)"),
        ("end", "time, or GPS time", REQ, "end"),
        ("satellite", "name (e.g. G13)", "—", "gnss_ranges: the faulty satellite"),
        ("draw", "table", "—", "Monte-Carlo on recorded logs: what each run draws"),
    ]),
    "faults.draw": _s("[faults.draw]", "What a Monte-Carlo campaign on recorded logs draws per run.", [
        ("start", "[low, high] times", "the fault's own", "onset range (the window's length kept)"),
        ("components", "list of component lists", "the fault's own", "component sets to choose from"),
        ("shapes", "list of tables", "the fault's own", "shapes to choose from"),
        ("satellites", "list of names", "none", "satellites to choose from (raw GNSS logs)"),
    ]),
    "faults.draw.shapes": _s("[[faults.draw.shapes]]", "One drawn shape.", [
        ("kind", "step, ramp, quadratic", REQ, "shape"),
        ("magnitude", "[low, high] quantities", REQ, "size range (uniform)"),
    ]),
    "detectors": _s("detectors = [{…}]", "A detector on a sub-filter's or sensor's innovations.", [
        ("name", "name", "its kind", "unique within its list (a `decision` names it)"),
        ("kind", _DETECTOR_KINDS, REQ, "test"),
        ("pf", "probability", REQ, "false-alarm probability per test"),
        ("pm", "probability", "—", "missed-detection probability (sprt, joint)"),
        ("variance", "known, sample", "known", "SPRT variance"),
        ("min_samples", "integer", "1 (known), 20 (sample)", "SPRT: samples since its last reset before it may alarm"),
    ]),
    "federated": _s("[federated]", "Federated filter (papers 001, 003).", [
        ("mode", "reset, no_reset", REQ, "information-sharing mode"),
        ("master_share", "number ≥ 0", REQ, "master's information share β_m (Σβ_i + β_m = 1)"),
        ("subfilters", "list of tables", REQ, "one per sensor (`[[federated.subfilters]]`)"),
        ("isolated", "track, predict, update", "track", "what an isolated sub-filter does"),
        ("isolate", "bool", "true", "false: detectors report but never isolate"),
    ]),
    "federated.subfilters": _s("[[federated.subfilters]]", "One federated sub-filter.", [
        ("sensor", "name", REQ, "its sensor"),
        ("share", "number", REQ, "information share β_i"),
        ("detectors", "list of detectors", "none", "detectors on its residuals"),
        ("isolation", "detector name", "—", "the detector whose alarm isolates it"),
    ]),
    "centralized": _s("[centralized]", "Centralized filter (papers 002, 003).", [
        ("policy", "exclude, latched, fading", REQ, "what an alarm does"),
        ("sensors", "list of tables", REQ, "sensors updating the filter (`[[centralized.sensors]]`)"),
        ("fading", "number > 1", "1", "fading factor (policy fading)"),
        ("fading_duration", "time", "0 s", "how long it applies after a detection"),
        ("confirm", "time", "0 s", "how long a restarted component stays below threshold before its fault is over"),
        ("altitude_fusion", "table", "—", "paper 003's weighted altitude fusion with a fault matrix"),
        ("isolate", "bool", "true", "false: the policy reports but never excludes"),
    ]),
    "centralized.sensors": _s("[[centralized.sensors]] / [[loosely_coupled.sensors]]", "A sensor of a centralized or loosely coupled filter with its detectors.", [
        ("sensor", "name", REQ, "its sensor"),
        ("detectors", "list of detectors", "none", "detectors on its block of the innovation"),
        ("decision", "detector name", "—", "the detector whose alarms act"),
    ]),
    "centralized.altitude_fusion": _s("[centralized.altitude_fusion]", "Altitude fused from several sensors.", [
        ("sensors", "list of names", REQ, "the height sensors fused"),
        ("samples", "integer", "20", "window N of the variance estimates"),
        ("estimate", "mean_square, variance", "mean_square", "how each sensor's variance is estimated (paper eq. 35: variance)"),
    ]),
    "state_chi2": _s("[state_chi2]", "State chi-square test of the navigation solution (two alternating propagators).", [
        ("pf", "probability", REQ, "false-alarm probability per epoch"),
        ("reset_every", "time", REQ, "period between resets of each propagator"),
        ("min_age", "time", "reset_every", "age before a propagator is tested"),
        ("states", "list of state names", "all", "tested states (att_e … clock_drift)"),
    ]),
    "modes": _s("[modes]", "Paper 003's navigation modes by distance to a target.", [
        ("gnss", "name", REQ, "the GNSS sensor"),
        ("target", "[east, north] lengths", REQ, "target position from the start point"),
        ("radius", "length", REQ, "distance at which the terminal modes start"),
        ("q1", "list of names", REQ, "sensors of mode q1"),
        ("q2", "list of names", REQ, "sensors of mode q2"),
        ("q3", "list of names", REQ, "sensors of mode q3"),
    ]),
    "variants": _s("[[variants]]", "A configuration compared on the same measurements.", [
        ("name", "name", REQ, "unique variant name"),
        ("set", "table of field path = value", "{}", "filter fields changed (architecture tables, state_chi2; never what is measured)"),
    ]),
    "tight": _s("[tight]", "Tightly coupled INS/GNSS with satellite FDE (paper 001; recorded logs with [tight.strapdown]).", [
        ("sensor", "name", REQ, "the gnss_ranges sensor"),
        ("fde", "ls_precheck, innovation, gnss_filter, separation, none", REQ, "where satellite FDE sits"),
        ("alpha", "probability", REQ, "false-alarm probability of the global test"),
        ("k", "number", "z(1 − α/2)", "w-test critical value"),
        ("ls_test", "global, wtest, both, auto", "global", "ls_precheck's detection test (data snooping: wtest)"),
        ("rates", "bool", "true", "use Doppler range rates"),
        ("accel_psd", "m²/s³", "1 m^2/s^3", "simulation: the filter's acceleration noise density"),
        ("strapdown", "table", "—", "a strapdown INS on recorded IMU samples"),
        ("integrity", "table", "—", "filter protection levels"),
        ("range_states", "\"white\", \"auto\" or a table", "white", "recorded logs: per-satellite Gauss-Markov range-error states (auto: estimated from the log's residuals)"),
    ]),
    "tight.range_states": _s("[tight.range_states]", "Time-correlated pseudorange errors as one first-order Gauss-Markov state per satellite in the strapdown tight filter and its sub-filters.", [
        ("fraction", "number in [0, 1)", REQ, "share of each pseudorange's variance (the sensor's σ by elevation, squared) that is correlated; the rest stays white"),
        ("tau", "time (s)", REQ, "correlation time"),
    ]),
    "tight.integrity": _s("[tight.integrity]", "Filter protection levels (solution separation, LPV-200 defaults).", [
        ("p_sat", "probability", "1e-5", "prior probability of a satellite fault per epoch"),
        ("p_hmi_vert", "probability", "LPV-200", "vertical integrity risk allocation"),
        ("p_hmi_hor", "probability", "LPV-200", "horizontal integrity risk allocation"),
        ("p_fa_vert", "probability", "3.9e-6", "vertical false-alarm allocation"),
        ("p_fa_hor", "probability", "LPV-200", "horizontal false-alarm allocation"),
        ("tol_pl", "number (m)", "ADD's", "protection-level search tolerance"),
        ("range_errors", "\"white\", \"overbound\" or a number", "white", "time correlation of the range errors: a variance factor (overbound: from the log's residuals)"),
    ]),
    "strapdown": _s("[loosely_coupled] / [tight.strapdown]", "The strapdown INS on a recorded IMU (the keys both share; [loosely_coupled] adds its own below).", [
        ("imu", "table", REQ, "IMU noise figures"),
        ("imu_axes", "three of forward, back, right, left, down, up, or \"auto\"", "— (or mounting)", "body frame: where the IMU's x, y, z axes point; \"auto\": from the log (gravity, and the accelerations along and across the GNSS track; a ground vehicle)"),
        ("mounting", "angle×3", "— (or imu_axes)", "roll, pitch, yaw of the IMU axes in the body (forward-right-down)"),
        ("boresight", "angle×3, or \"auto\"", "0; loosely coupled: the log's where it shows one", "small misalignment (roll, pitch, yaw) on top of imu_axes or mounting; \"auto\": pitch and yaw from the log (loosely coupled); not given with imu_axes, a pitch or yaw the log shows beyond 1° and 4σ, fitting the log better than none, is estimated (\"0 deg\" keeps none)"),
        ("lever_arm", "length×3", REQ, "antenna from the IMU, body frame"),
        ("imu_time_offset", "time, or \"auto\"", "0 s; loosely coupled: the log's where it shows one", "added to the IMU time stamps; \"auto\": from the log (loosely coupled); not given, an offset the log's innovations show beyond 0.02 s and 4σ is estimated (\"0 s\" keeps none; not on meter-level positions alone)"),
        ("alignment", "table", REQ, "initial alignment"),
    ]),
    "loosely_coupled": _s("[loosely_coupled]", "Loosely coupled INS/GNSS on recorded logs: the strapdown keys above and these.", [
        ("sensors", "list of tables", REQ, "GNSS channels and their detectors (`[[loosely_coupled.sensors]]`, fields as centralized sensors)"),
        ("zupt", "table", "—", "zero-velocity updates at rest detected from the IMU"),
        ("nhc", "table", "—", "non-holonomic constraint (wheeled vehicles)"),
        ("witness", "bool", "true", "a channel's alarm excludes it only when another GNSS channel of the epoch passes (with one GNSS channel, e.g. positions only, the alarm acts)"),
        ("isolate_components", "bool", "true", "an alarming measurement keeps the components that pass"),
        ("accommodate", "bool", "true", "a held step is used as a relative fix"),
        ("isolate", "bool", "true", "false: detectors report but every measurement is used"),
        ("convergence", "number", "3", "converged once every channel's predicted σ is within this multiple of its own"),
        ("noise_scale", "\"auto\" or number", "auto", "scale of the GNSS σ in the tests (auto: from the innovations, clamped to [1, 10]; a solution quality worse than the best the receiver gave, e.g. RTK float beside fixed, gets its own from its own fixes; positions alone: at least the fixes' own scatter over the σ they write, up to what the tested fixes say, where that ratio exceeds 1.5)"),
        ("position_correlation", "\"auto\" or time", "0 s", "correlation time of the GNSS position errors (Gauss-Markov): in the update each fix counts as the fraction (1 − ρ)/(1 + ρ) of an independent fix (its position variance × (1 + ρ)/(1 − ρ)), ρ = exp(−Δt/τ), Δt the fix interval; 0: white; auto: the errors' white and correlated parts and τ read from the log's fixes against the receiver's velocities, the variance × (σ_w² + σ_g² (1 + ρ)/(1 − ρ))/(σ_w² + σ_g²) (white where the log shows no correlation or has no velocities)"),
    ]),
    "strapdown.imu": _s("[loosely_coupled.imu] / [tight.strapdown.imu]", "IMU noise figures, per IMU axis.", [
        ("gyro_noise", "angular rate density ×3 (deg/s/sqrt(Hz), deg/sqrt(h)), or \"auto\"", REQ, "angle random walk; \"auto\": from the log's rest intervals (loosely coupled)"),
        ("accel_noise", "acceleration density ×3 (mg/sqrt(Hz), m/s/sqrt(h)), or \"auto\"", REQ, "velocity random walk; \"auto\" as gyro_noise"),
        ("gyro_bias", "angular rate", REQ, "bias instability σ"),
        ("accel_bias", "acceleration", REQ, "bias instability σ"),
        ("bias_tau", "time", REQ, "bias correlation time"),
        ("gyro_scale", "fraction", "0 ppm", "gyro scale-factor σ"),
        ("accel_scale", "fraction", "0 ppm", "accelerometer scale-factor σ"),
    ]),
    "strapdown.alignment": _s("[loosely_coupled.alignment] / [tight.strapdown.alignment]", "Initial alignment.", [
        ("speed", "velocity", REQ, "GNSS speed above which heading is taken from the course and navigation starts (and at least 5× the velocity's σ, where the log reaches it)"),
        ("heading", "angle", "from the course", "a known initial heading"),
        ("static_speed", "velocity", "0.05 m/s", "rest below this (or 2.5× the receiver's velocity σ), where the velocities average to zero and the IMU is at rest too (the longest such stretch before the alignment)"),
        ("gyro_bias", "bool", "true", "gyro biases from the static start"),
        ("sigma_level", "angle", REQ, "initial roll and pitch σ"),
        ("sigma_heading", "angle", REQ, "initial heading σ"),
        ("sigma_position", "length", REQ, "initial position σ per axis"),
        ("sigma_velocity", "velocity", REQ, "initial velocity σ per axis"),
    ]),
    "constraint": _s("[loosely_coupled.zupt] / [loosely_coupled.nhc]", "A vehicle constraint used as a measurement.", [
        ("noise", "velocity, one or per component", REQ, "σ (zupt: north, east, down; nhc: body right, down)"),
        ("detectors", "list of detectors", "none", "detectors on its innovation"),
        ("decision", "detector name", "—", "the detector whose alarm drops it for the epoch"),
        ("window", "time", "0.5 s", "zupt: IMU window rest is detected over"),
        ("threshold", "zupt: acceleration; nhc: velocity", REQ, "zupt: largest σ of the specific force; nhc: least speed to apply"),
        ("rate_threshold", "angular rate", REQ, "zupt: largest mean rate; nhc: largest yaw rate to apply"),
    ]),
    "ultra_tight": _s("[ultra_tight]", "Vector tracking with AIME detection (paper 004).", [
        ("sensor", "name", REQ, "the gnss_ranges sensor"),
        ("satellites", "list of names", REQ, "tracked satellites"),
        ("method", "m1, m2, m3", REQ, "AIME on the navigation filter, the prefilter, or two-stage"),
        ("pf", "probability", REQ, "false-alarm probability per test"),
        ("cn0", "carrier to noise (dB-Hz)", REQ, "every channel's C/N0"),
        ("integration", "time", "20 ms", "coherent integration = prefilter step"),
        ("nav_input", "discriminator, prefilter", "discriminator", "what the navigation filter takes per epoch"),
        ("nav_window", "time", "20 s", "M1 window"),
        ("prefilter_window", "time", "20 s", "M2 window"),
        ("stage1_window", "time", "2 s", "M3 stage-1 window"),
        ("stage2_window", "time", "10 s", "M3 stage-2 window"),
        ("stage_q", "number", "10", "M3 statistic filter random-walk variance"),
        ("stage_period", "time", "1 s", "M3 stage-1 statistic period"),
        ("stage_r0", "number", "1", "M3 statistic filter starting R₀"),
        ("fading_b", "number in [0.9, 0.999]", "0.99", "M3 Allan-variance fading factor"),
        ("jerk_psd", "Hz²/s³", "1 Hz^2/s^3", "prefilter frequency-rate random walk"),
        ("code_psd", "chips²/s", "0 chips^2/s", "prefilter code-phase random walk"),
        ("spacing", "number (chips)", "1", "early-late spacing"),
        ("exclude", "bool", "true", "an alarming channel stops feeding the filter"),
        ("arm_after", "time", "30 s", "statistics recorded but never alarm before this"),
    ]),
    "source.loosely_coupled": _s("[source] (loosely coupled)", "Recorded logs of a loosely coupled scenario.", [
        ("gnss", "path or table", REQ, "the GNSS solution log ([source.gnss])"),
        ("imu", "table", REQ, "the IMU log ([source.imu])"),
        ("reference", "path or table (as gnss)", "none", "positions to score against: an RTKLIB .pos, or any solution format [source.gnss] takes (NMEA, UBX, navfdi solution.csv, a CSV with columns)"),
        ("reference_quality", "list of integers", "[1]", "the reference's solution qualities used (1 RTK fixed); not for a CSV reference (every epoch used)"),
        ("reference_epochs", "auto, held_out, inputs", "auto", "where the reference is scored"),
    ]),
    "source.tight": _s("[source] (tight)", "Recorded logs of a tight scenario with [tight.strapdown].", [
        ("rinex_obs", "path", REQ, "RINEX observations"),
        ("rinex_nav", "path", REQ, "RINEX navigation data"),
        ("imu", "table", REQ, "the IMU log ([source.imu])"),
        ("reference", "path or table (as gnss)", "none", "positions to score against (as the loosely coupled source's)"),
        ("reference_quality", "list of integers", "[1]", "the reference's solution qualities used"),
    ]),
    "source.gnss": _s("[source.gnss]", "A GNSS solution log (`gnss = \"file\"` is `{ file = \"file\" }`).", [
        ("file", "path", REQ, "the log (format told from the file when not given)"),
        ("format", "pos, solution, nmea, csv, rinex, ubx, gnsslogger, rosbag", "from the file", "RTKLIB .pos, navfdi solution.csv, NMEA 0183, any CSV, RINEX files solved as read, a u-blox binary log's NAV-PVT solutions, an Android GnssLogger file's Fix records, or a ROS bag's NavSatFix topic"),
        ("columns", "table", "— (csv: required)", "csv: time, lat, lon, height or height_msl (or ecef: x, y, z), sd, vel, sd_vel (or sd_ecef, vel_ecef, sd_vel_ecef), satellites column names"),
        ("time_scale", "gpst, utc, unix", "gpst (rosbag: unix)", "csv: the ISO time column's scale, or unix: a numeric time column is Unix time (UTC since 1970-01-01, turned into GPS time with the leap seconds) instead of GPS seconds; rosbag: the stamps' scale (ROS time is Unix time)"),
        ("time_unit", "s, ms, us, ns", "s", "csv: a numeric time column's unit"),
        ("gps_week", "integer", "—", "csv: the GPS week of a time column in seconds of week (as KF-GINS writes; or in time_unit, e.g. ms for u-blox's iTOW)"),
        ("header", "true, false", "true", "csv: the first line names the columns; false: columns numbered from 1"),
        ("delimiter", "one character, tab or whitespace", ",", "csv: the field separator (\"whitespace\": runs of spaces and tabs)"),
        ("date", "YYYY-MM-DD", "from RMC", "nmea: the UTC date when no RMC sentence gives it"),
        ("topic", "topic name", "the bag's only NavSatFix topic", "rosbag: the sensor_msgs/NavSatFix topic"),
        ("velocity_topic", "topic name", "none", "rosbag: a geometry_msgs/TwistWithCovarianceStamped or TwistStamped topic of the receiver's velocity (east, north, up), matched to the fixes by stamp"),
        ("provider", "GPS, FLP, NLP, …", "GPS", "gnsslogger: the location provider whose fixes are read (GPS: the GNSS chipset's; FLP: Android's fused location, which already uses the phone's IMU; GT in the Decimeter Challenge's ground_truth.csv)"),
        ("undulation", "number (m)", "—", "csv with height_msl: geoid height added"),
    ]),
    "source.gnss.rinex": _s("[source.gnss] format = \"rinex\"", "RINEX files solved by navfdi's SPP with FDE as the log is read.", [
        ("format", "rinex", REQ, "this form"),
        ("obs", "path", REQ, "RINEX observations"),
        ("nav", "path", REQ, "RINEX navigation data"),
        ("systems", "list of letters (G, E, C, J)", "[\"G\"]", "systems used"),
        ("elevation_mask", "angle", "10 deg", "mask"),
        ("weighting", "elevation, cn0, rtklib, auto", "auto", "σ model of the solve (`navfdi gnss --weighting`)"),
        ("noise", "auto or a factor", "auto", "σ factor of the solve, estimated from the file by default (`navfdi gnss --noise`)"),
        ("test", "global, wtest, both, auto", "global", "snapshot FDE detection test"),
    ]),
    "source.imu": _s("[source.imu]", "An IMU CSV log (plain or gzip) and its columns, an Android GnssLogger file's sensor records, or a ROS bag's Imu topic.", [
        ("file", "path", REQ, "the CSV (or GnssLogger file)"),
        ("topic", "topic name", "the bag's only Imu topic", "rosbag: the sensor_msgs/Imu topic"),
        ("format", "csv, gnsslogger, rosbag", "csv", "gnsslogger: an Android GnssLogger file's accelerometer and gyro records (uncalibrated where present; or the Smartphone Decimeter Challenge's device_imu.csv), put on GPS time by the file's own clock pairs; only file, max_gap and clock beside it"),
        ("clock", "path", "the IMU file", "gnsslogger: the file whose Raw records pair the phone's boot clock with GPS time (the Decimeter Challenge's device_gnss.csv beside its device_imu.csv)"),
        ("week", "column", "—", "GPS week column (with seconds of week)"),
        ("seconds", "column", "— (or time)", "GPS seconds (of week with week)"),
        ("time", "column", "— (or seconds)", "GPS seconds since 1980-01-06 (or Unix time with time_scale = \"unix\")"),
        ("time_scale", "gpst, unix, utc, boot", "gpst (rosbag: unix)", "rosbag: the stamps' scale (unix or gpst); csv: the time column's count: GPS seconds (or ISO 8601 date-times in GPS time, told from the first row; utc: ISO date-times in UTC); Unix time (UTC since 1970-01-01, turned into GPS time with the leap seconds); or boot: the IMU's own clock (e.g. since power-up), placed on GPS time by matching its turn rate to the GNSS track's, offset and, where the log tells it, rate (said in a warning)"),
        ("time_unit", "s, ms, us, ns", "s", "the time column's unit"),
        ("header", "true, false", "true", "the first line names the columns; false: columns are numbered from 1 (time = 1, gyro = [5, 6, 7])"),
        ("delimiter", "one character, tab or whitespace", ",", "the field separator (\";\", \"tab\", \" \", …; \"whitespace\": runs of spaces and tabs, as column-aligned text)"),
        ("gps_week", "integer", "—", "the GPS week of a seconds-of-week time column (seconds = …; as KF-GINS writes; or in time_unit, e.g. ms for u-blox's iTOW)"),
        ("gyro", "three columns", "— (csv: required)", "rates (or increments) in the IMU's x, y, z"),
        ("accel", "three columns", "— (csv: required)", "specific forces (or increments) in the IMU's x, y, z"),
        ("gyro_unit", "rad/s, deg/s", "rad/s", "gyro column unit"),
        ("accel_unit", "m/s^2, m/s2, g", "m/s^2", "accelerometer column unit"),
        ("kind", "rates, increments", "rates", "increments are divided by the sample interval"),
        ("max_gap", "time", "1 s", "largest sample interval accepted (longer gaps are refused; gaps over twice the median interval are bridged with the filter's noise raised, and said)"),
        ("time_repeats", "refuse, spread", "refuse", "samples sharing a time stamp (a logger stamping them in batches): refused with their line, or spread evenly from the stamp to the next"),
    ]),
}


def keys(section: str) -> set[str]:
    """The keys :data:`SECTIONS` allows in ``section`` (``"loosely_coupled"`` also takes the
    strapdown keys; ``"tight.strapdown"`` is the strapdown section)."""
    if section == "loosely_coupled":
        return set(SECTIONS["strapdown"].keys) | set(SECTIONS["loosely_coupled"].keys)
    if section == "tight.strapdown":
        return set(SECTIONS["strapdown"].keys)
    return set(SECTIONS[section].keys)
