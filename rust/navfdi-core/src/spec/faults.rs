//! Faults injected into a sensor's measurements (any source: simulated or recorded).

use super::check::bad;
use super::{Architecture, ScenarioSpec};
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// Fault shape over its window `[start, end)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// `magnitude`.
    Step,
    /// `magnitude · (t − start)`.
    Ramp,
    /// `magnitude · (t − start)²`.
    Quadratic,
}

/// A fault added to chosen components of a sensor's measurement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// Unique identifier.
    pub id: String,
    /// Sensor name.
    pub sensor: String,
    /// Component indices affected.
    pub components: Vec<usize>,
    /// Shape.
    pub kind: FaultKind,
    /// Size (SI unit of the component; per s for ramps, per s² for quadratics).
    pub magnitude: f64,
    /// Window start (s).
    pub start: f64,
    /// Window end (s), exclusive.
    pub end: f64,
    /// Satellite name (faults on a `gnss_ranges` sensor only), e.g. `G03`.
    #[serde(default)]
    pub satellite: Option<String>,
    /// What a Monte-Carlo campaign on recorded logs draws per run (None: the fault as given).
    #[serde(default)]
    pub draw: Option<FaultDraw>,
}

/// A fault's parameters drawn per Monte-Carlo run from the run's seed (uniformly): its start
/// (the window's length kept), its shape and size, and the components it affects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultDraw {
    /// Range of the start (s), `[lo, hi]`; None: the fault's own start.
    #[serde(default)]
    pub start: Option<[f64; 2]>,
    /// Shapes to choose from, each with its range of magnitude (SI, as `magnitude`); empty:
    /// the fault's own kind and magnitude.
    #[serde(default)]
    pub shapes: Vec<(FaultKind, [f64; 2])>,
    /// Component sets to choose from (indices, as `components`); empty: the fault's own.
    #[serde(default)]
    pub components: Vec<Vec<usize>>,
    /// Satellites to choose from (names, faults on a `gnss_ranges` sensor of recorded logs);
    /// empty: the fault's own.
    #[serde(default)]
    pub satellites: Vec<String>,
}

/// Stream of the fault draws: separate from the simulator's noise streams of the same run.
pub const DRAW_STREAM: u64 = 0x00d2_a3f1_7c5b_9e41;

impl FaultSpec {
    /// This fault with its [`FaultSpec::draw`] drawn from `rng` (itself when there is none).
    pub fn drawn(&self, rng: &mut rand_chacha::ChaCha8Rng) -> FaultSpec {
        use rand::RngExt;
        let mut f = self.clone();
        let Some(d) = &self.draw else {
            return f;
        };
        if let Some([lo, hi]) = d.start {
            let len = self.end - self.start;
            f.start = lo + (hi - lo) * rng.random::<f64>();
            f.end = f.start + len;
        }
        if !d.shapes.is_empty() {
            let (kind, [lo, hi]) = d.shapes[rng.random_range(0..d.shapes.len())];
            f.kind = kind;
            f.magnitude = lo + (hi - lo) * rng.random::<f64>();
        }
        if !d.components.is_empty() {
            f.components = d.components[rng.random_range(0..d.components.len())].clone();
        }
        if !d.satellites.is_empty() {
            f.satellite = Some(d.satellites[rng.random_range(0..d.satellites.len())].clone());
        }
        f.draw = None;
        f
    }
}

impl ScenarioSpec {
    fn validate_draw(&self, p: &str, f: &FaultSpec, d: &FaultDraw, dim: usize) -> Result<()> {
        if !self.runs_on_logs() {
            return Err(bad(
                format!("{p}.draw"),
                "drawn faults run on recorded logs (architecture loosely_coupled, or tight with tight.strapdown); a simulated campaign varies a fault with --sweep",
            ));
        }
        let range = |q: String, r: [f64; 2]| -> Result<()> {
            if !(r[0].is_finite() && r[1].is_finite() && r[0] <= r[1]) {
                return Err(bad(
                    q,
                    format!(
                        "[{}, {}]: expected finite [low, high] with low <= high",
                        r[0], r[1]
                    ),
                ));
            }
            Ok(())
        };
        if let Some(r) = d.start {
            range(format!("{p}.draw.start"), r)?;
            let len = f.end - f.start;
            if r[0] < 0.0 || r[1] + len > self.duration {
                return Err(bad(
                    format!("{p}.draw.start"),
                    format!(
                        "[{}, {}] s with the fault's {len} s window leaves the run's 0–{} s",
                        r[0], r[1], self.duration
                    ),
                ));
            }
        }
        for (j, (_, r)) in d.shapes.iter().enumerate() {
            range(format!("{p}.draw.shapes[{j}].magnitude"), *r)?;
        }
        for (j, set) in d.components.iter().enumerate() {
            let q = format!("{p}.draw.components[{j}]");
            if set.is_empty() {
                return Err(bad(q, "an empty component set"));
            }
            for (k, &c) in set.iter().enumerate() {
                if c >= dim || set[..k].contains(&c) {
                    return Err(bad(q, format!("component index {c} is out of range or repeated (sensor {:?} has {dim} components)", f.sensor)));
                }
            }
        }
        for (j, name) in d.satellites.iter().enumerate() {
            let q = format!("{p}.draw.satellites[{j}]");
            if f.satellite.is_none() {
                return Err(bad(
                    q,
                    "only a fault on a satellite (with satellite = \"G13\", …) draws its satellite",
                ));
            }
            if crate::gnss::broadcast::Sat::parse(name).is_none() {
                return Err(bad(
                    q,
                    format!("{name:?} is not a satellite name (e.g. \"G13\")"),
                ));
            }
        }
        Ok(())
    }

    /// The scenario of Monte-Carlo run `run` of a campaign seeded `seed`: every fault with a
    /// `draw` drawn from ChaCha8 `(seed, run ^ DRAW_STREAM)`.
    pub fn drawn(&self, seed: u64, run: u64) -> ScenarioSpec {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(run ^ DRAW_STREAM);
        let mut out = self.clone();
        out.faults = self.faults.iter().map(|f| f.drawn(&mut rng)).collect();
        out
    }
}

impl FaultSpec {
    /// Fault value at time `t` (s).
    pub fn value(&self, t: f64) -> f64 {
        if t < self.start || t >= self.end {
            return 0.0;
        }
        let d = t - self.start;
        match self.kind {
            FaultKind::Step => self.magnitude,
            FaultKind::Ramp => self.magnitude * d,
            FaultKind::Quadratic => self.magnitude * d * d,
        }
    }
}

impl ScenarioSpec {
    /// Every fault: sensor, components, shape, satellite, window, and a channel that sees it.
    pub(super) fn validate_faults(&self) -> Result<()> {
        for (i, f) in self.faults.iter().enumerate() {
            let p = format!("faults[{i}]");
            if self.faults[..i].iter().any(|o| o.id == f.id) {
                return Err(bad(
                    format!("{p}.id"),
                    format!("{:?} is used by an earlier fault", f.id),
                ));
            }
            let Some(si) = self.sensor_index(&f.sensor) else {
                return Err(bad(
                    format!("{p}.sensor"),
                    format!(
                        "{:?} is not a sensor (known: {})",
                        f.sensor,
                        self.sensor_names()
                    ),
                ));
            };
            let dim = self.sensors[si].kind.dim();
            if f.components.is_empty() {
                return Err(bad(
                    format!("{p}.components"),
                    "at least one component is required",
                ));
            }
            for (j, c) in f.components.iter().enumerate() {
                if f.components[..j].contains(c) {
                    return Err(bad(
                        format!("{p}.components[{j}]"),
                        format!(
                            "component {:?} is listed twice (the fault would be added twice)",
                            self.sensors[si]
                                .kind
                                .components()
                                .get(*c)
                                .copied()
                                .unwrap_or("?")
                        ),
                    ));
                }
                if *c >= dim {
                    return Err(bad(
                        format!("{p}.components[{j}]"),
                        format!(
                            "index {c} out of range for sensor {:?} with {dim} components",
                            f.sensor
                        ),
                    ));
                }
            }
            if !f.magnitude.is_finite() {
                return Err(bad(format!("{p}.magnitude"), "must be finite"));
            }
            if let Some(d) = &f.draw {
                self.validate_draw(&p, f, d, dim)?;
            }
            match (&self.sensors[si].ranges, &f.satellite) {
                // On recorded logs the satellites are the RINEX file's: the source checks the
                // name.
                (Some(_), Some(sat)) if self.runs_on_logs() => {
                    if crate::gnss::broadcast::Sat::parse(sat).is_none() {
                        return Err(bad(
                            format!("{p}.satellite"),
                            format!("{sat:?} is not a satellite name (a system letter and a number, e.g. \"G13\", \"E05\")"),
                        ));
                    }
                }
                (Some(r), Some(sat)) => {
                    let orbits = r.orbits();
                    if !orbits.iter().any(|o| &o.name == sat) {
                        return Err(bad(
                            format!("{p}.satellite"),
                            format!(
                                "{sat:?} is not a satellite of sensor {:?} ({} to {})",
                                f.sensor,
                                orbits.first().map_or("", |o| o.name.as_str()),
                                orbits.last().map_or("", |o| o.name.as_str())
                            ),
                        ));
                    }
                }
                (Some(_), None) => {
                    return Err(bad(
                        format!("{p}.satellite"),
                        format!("missing: a fault on the gnss_ranges sensor {:?} names its satellite, e.g. \"G03\"", f.sensor),
                    ))
                }
                (None, Some(_)) => {
                    return Err(bad(
                        format!("{p}.satellite"),
                        format!("only faults on a gnss_ranges sensor name a satellite; {:?} is {:?}", f.sensor, self.sensors[si].kind),
                    ))
                }
                (None, None) => {}
            }
            if !(f.start.is_finite() && f.end.is_finite() && f.start < f.end) {
                return Err(bad(
                    p.clone(),
                    format!(
                        "window start = {}, end = {} must be finite with start < end",
                        f.start, f.end
                    ),
                ));
            }
            let last = (self.epochs().saturating_sub(1)) as f64 * self.dt;
            if f.start > last || f.end <= 0.0 {
                return Err(bad(
                    p.clone(),
                    format!(
                        "window [{}, {}] s lies outside the run, whose epochs span [0, {last}] s",
                        f.start, f.end
                    ),
                ));
            }
            if !self.channels().iter().any(|ch| ch.sensor == f.sensor) {
                // A misspelt sensor in the filter's configuration (or no satellite to track) is
                // the cause to name, not the fault.
                self.check_channel_sensors()?;
                return Err(bad(
                    format!("{p}.sensor"),
                    format!(
                        "no {} uses sensor {:?}, so the fault would never be seen; add one for it or remove the fault",
                        match self.architecture {
                            Architecture::Federated => "sub-filter",
                            Architecture::Centralized => "centralized.sensors entry",
                            Architecture::Tight => "tight filter (tight.sensor)",
                            Architecture::UltraTight => "ultra-tight filter (ultra_tight.sensor)",
                            Architecture::LooselyCoupled => "loosely_coupled.sensors entry",
                        },
                        f.sensor
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every sensor the architecture's configuration names exists (and an ultra-tight filter
    /// tracks at least one satellite); errors name the configuration field.
    pub(super) fn check_channel_sensors(&self) -> Result<()> {
        let names: Vec<(String, &str)> = match self.architecture {
            Architecture::Federated => self
                .federated
                .iter()
                .flat_map(|f| {
                    f.subfilters.iter().enumerate().map(|(i, s)| {
                        (
                            format!("federated.subfilters[{i}].sensor"),
                            s.sensor.as_str(),
                        )
                    })
                })
                .collect(),
            Architecture::Centralized => self
                .centralized
                .iter()
                .flat_map(|c| {
                    c.sensors.iter().enumerate().map(|(i, s)| {
                        (
                            format!("centralized.sensors[{i}].sensor"),
                            s.sensor.as_str(),
                        )
                    })
                })
                .collect(),
            Architecture::LooselyCoupled => self
                .loosely_coupled
                .iter()
                .flat_map(|l| {
                    l.sensors.iter().enumerate().map(|(i, s)| {
                        (
                            format!("loosely_coupled.sensors[{i}].sensor"),
                            s.sensor.as_str(),
                        )
                    })
                })
                .collect(),
            Architecture::Tight => self
                .tight
                .iter()
                .map(|t| ("tight.sensor".to_string(), t.sensor.as_str()))
                .collect(),
            Architecture::UltraTight => {
                if let Some(u) = &self.ultra_tight {
                    if u.satellites.is_empty() {
                        return Err(bad(
                            "ultra_tight.satellites",
                            "at least one satellite to track is required",
                        ));
                    }
                }
                self.ultra_tight
                    .iter()
                    .map(|u| ("ultra_tight.sensor".to_string(), u.sensor.as_str()))
                    .collect()
            }
        };
        for (path, name) in names {
            if self.sensor_index(name).is_none() {
                return Err(bad(
                    path,
                    format!("{name:?} is not a sensor (known: {})", self.sensor_names()),
                ));
            }
        }
        Ok(())
    }
}
