//! RINEX 3 observation and navigation files, read with the `rinex` crate.
//!
//! The crate parses; this module guards it and converts its records into [`ObsData`] and
//! [`NavData`]. Three guards work around what the crate (0.24) does with real files:
//!
//! 1. **Header normalisation.** Its header parser silently drops observation types it does not
//!    know, such as Septentrio's `X1` (receiver channel) pseudo-observable, which shifts every
//!    following column by one (C1C would then hold the channel number). Before parsing, every
//!    such code in `SYS / # / OBS TYPES` is renamed to a placeholder the parser keeps
//!    (`WZ0`, `WZ1`, …, a "power" type no real file uses); those columns are then dropped.
//! 2. **Structure check with line numbers.** The crate accepts a truncated file (it returns the
//!    epochs before the cut) and some malformed ones without an error, and its errors carry no
//!    line numbers. A pass over the text checks the header (`RINEX VERSION / TYPE`, version
//!    3.xx, `END OF HEADER`), each epoch line, the satellite lines each announces, the field
//!    count against the header and that every field is a number; navigation records must
//!    have their continuation lines. Failures name the file, the line and what was expected.
//!    Every header line must carry a label, and a panic inside the crate's parser (it has
//!    some on malformed input) becomes a format error.
//! 3. **Health and clocks are interpreted here**: its `sv_healthy()` reports every Galileo
//!    record unhealthy, and its clock correction returns nothing before t_oc; see
//!    [`super::broadcast`].
//!
//! Reading the text and the structure checks of guard 2 are in [`super::rinex_text`].

use super::atmosphere::Klobuchar;
use super::broadcast::{Ephemeris, GpsTime, Sat, Sys};
pub use super::rinex_text::read_text;
use super::rinex_text::{
    check_nav_body, check_obs_body, check_version, format_err, header_end, label, rinex4_nav,
};
use crate::error::Result;
use nalgebra::Vector3;
use rinex::navigation::NavMessageType;
use rinex::prelude::{Constellation, Rinex, TimeScale};
use std::collections::{BTreeMap, HashMap};
use std::io::BufReader;

/// One observation: satellite, observable index into [`ObsData::codes`], value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Obs {
    /// Satellite.
    pub sat: Sat,
    /// Index into [`ObsData::codes`] (e.g. `C1C`).
    pub code: u16,
    /// Value (m for pseudoranges, cycles for phase, Hz for Doppler, dB-Hz for C/N0).
    pub value: f64,
}

/// One observation epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct ObsEpoch {
    /// Receiver time tag (GPST).
    pub time: GpsTime,
    /// Epoch flag (0 OK, 1 power failure before this epoch).
    pub flag: u8,
    /// Observations, satellite by satellite.
    pub obs: Vec<Obs>,
}

/// An observation file.
#[derive(Debug, Clone, PartialEq)]
pub struct ObsData {
    /// RINEX version (`3.04`).
    pub version: String,
    /// Observable names, indexed by [`Obs::code`].
    pub codes: Vec<String>,
    /// Header observation types per system letter, as in the file (placeholders excluded).
    pub header_codes: BTreeMap<char, Vec<String>>,
    /// Observation types that were dropped (e.g. `G:X1`).
    pub dropped_codes: Vec<String>,
    /// `APPROX POSITION XYZ` (m), if present and non-zero.
    pub approx_position: Option<Vector3<f64>>,
    /// Receiver type from `REC # / TYPE / VERS`.
    pub receiver: String,
    /// Epochs with flag 0 or 1, in time order.
    pub epochs: Vec<ObsEpoch>,
}

impl ObsData {
    /// Index of an observable name, if any observation uses it.
    pub fn code_index(&self, name: &str) -> Option<u16> {
        self.codes.iter().position(|c| c == name).map(|i| i as u16)
    }
}

/// A navigation file: ephemerides per satellite and the GPS Klobuchar coefficients.
#[derive(Debug, Clone, PartialEq)]
pub struct NavData {
    /// RINEX version.
    pub version: String,
    /// Ephemerides per satellite (systems GPS, Galileo, BeiDou, QZSS).
    pub ephemerides: BTreeMap<Sat, Vec<Ephemeris>>,
    /// GPS Klobuchar `[α₀..α₃, β₀..β₃]` from the header, if present.
    pub klobuchar: Option<Klobuchar>,
    /// Records per system letter as read (all systems, incl. those not positioned).
    pub records: BTreeMap<char, usize>,
    /// Records skipped because a required orbit field is missing or the orbit is impossible
    /// (√A outside 1000–10 000 √m, eccentricity ≥ 0.9).
    pub incomplete: usize,
}

/// The `rinex` crate's parser, with a panic inside it (it has some on malformed input, e.g.
/// an empty satellite field in a header line) turned into a format error.
fn crate_parse(path: &str, text: &str) -> Result<Rinex> {
    let parsed = std::panic::catch_unwind(|| Rinex::parse(&mut BufReader::new(text.as_bytes())));
    match parsed {
        Ok(Ok(r)) => Ok(r),
        Ok(Err(e)) => Err(format_err(
            path,
            None,
            format!("the RINEX parser failed: {e}"),
        )),
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(format_err(
                path,
                None,
                format!("the RINEX parser stopped on malformed content ({msg}); check the header and records"),
            ))
        }
    }
}

/// Normalised header text, placeholder → original type names, type counts per system.
type Normalised = (String, HashMap<String, String>, HashMap<char, usize>);

/// Rename unknown observation types in `SYS / # / OBS TYPES` (see the module docs); returns
/// the new header text (the `end` lines up to `END OF HEADER`), the placeholder → original
/// names and the header's type counts per system.
fn normalise_obs_header(path: &str, lines: &[&str], end: usize) -> Result<Normalised> {
    let lines = &lines[..end];
    let mut out = String::with_capacity(lines.iter().map(|l| l.len() + 1).sum());
    let mut renamed = HashMap::new();
    let mut counts = HashMap::new();
    let mut current = ' ';
    let mut k = 0usize;
    // The file's system (RINEX VERSION / TYPE, column 41: G, R, E, C, J, I, S or M).
    let file_sys = lines
        .iter()
        .find(|l| label(l) == "RINEX VERSION / TYPE")
        .and_then(|l| l.get(40..41))
        .and_then(|c| c.chars().next())
        .unwrap_or('M');
    for (i, line) in lines.iter().enumerate() {
        if label(line) == "TIME OF FIRST OBS" {
            out.push_str(&first_obs_time_system(path, i + 1, line, file_sys)?);
            out.push('\n');
            continue;
        }
        if i < end && label(line) == "SYS / # / OBS TYPES" {
            let mut l: Vec<u8> = line.as_bytes().to_vec();
            let sys = line.chars().next().unwrap_or(' ');
            if sys != ' ' {
                current = sys;
                let n: usize = line.get(3..6).unwrap_or("").trim().parse().map_err(|_| {
                    format_err(
                        path,
                        Some(i + 1),
                        "SYS / # / OBS TYPES: the number of types (columns 4–6) is not an integer",
                    )
                })?;
                counts.insert(current, n);
            }
            for f in 0..13 {
                let (a, b) = (7 + 4 * f, 10 + 4 * f);
                let Some(code) = line.get(a..b) else { break };
                let code = code.trim();
                if code.is_empty() {
                    continue;
                }
                let first = code.chars().next().unwrap_or(' ');
                if !matches!(first, 'C' | 'L' | 'D' | 'S') {
                    let ph = format!("WZ{}", char::from_digit((k % 36) as u32, 36).unwrap_or('0'));
                    k += 1;
                    renamed.insert(format!("{current}:{ph}"), format!("{current}:{code}"));
                    l[a..b].copy_from_slice(ph.as_bytes());
                }
            }
            out.push_str(std::str::from_utf8(&l).unwrap_or(line));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    Ok((out, renamed, counts))
}

/// The `TIME OF FIRST OBS` line with its time system (columns 49–51) made explicit for the
/// rinex crate, which reads a blank field as TAI (19 s off GPS time) and fails on `GLO`
/// without naming the line. The format: blank means the file's single system's time (GPS
/// for GPS and for mixed files); `GLO` is UTC (the crate's `UTC`, converted to GPS time with
/// the leap seconds). An unknown system is an error naming the line.
fn first_obs_time_system(path: &str, line_no: usize, line: &str, file_sys: char) -> Result<String> {
    let field = line.get(48..51).unwrap_or("").trim();
    let scale = match field {
        "" => match file_sys {
            'E' => "GAL",
            'C' => "BDT",
            'J' => "QZS",
            'R' => "UTC",
            _ => "GPS",
        },
        "GPS" | "GAL" | "BDT" | "QZS" => field,
        "GLO" | "UTC" => "UTC",
        other => {
            return Err(format_err(
                path,
                Some(line_no),
                format!("TIME OF FIRST OBS: time system {other:?} (columns 49–51) is not one of GPS, GLO, GAL, BDT, QZS"),
            ))
        }
    };
    let mut l: Vec<char> = line.chars().collect();
    while l.len() < 60 {
        l.push(' ');
    }
    let padded: String = format!("{scale:<3}");
    for (j, c) in padded.chars().enumerate() {
        l[48 + j] = c;
    }
    Ok(l.into_iter().collect())
}

fn to_sat(sv: &rinex::prelude::SV) -> Option<Sat> {
    Sat::parse(&format!("{sv}"))
}

fn gpst(e: &rinex::prelude::Epoch, scale: TimeScale) -> GpsTime {
    let (w, ns) = e.to_time_scale(scale).to_time_of_week();
    GpsTime::new(w as i64, ns as f64 * 1e-9)
}

/// Read a RINEX 3 observation file (`path` for messages, `text` its content).
pub fn parse_obs(path: &str, text: &str) -> Result<ObsData> {
    parse_obs_in(path, text, OBS_CHUNK_EPOCHS)
}

/// [`parse_obs`] with the rinex crate given `chunk` epochs at a time.
fn parse_obs_in(path: &str, text: &str, chunk: usize) -> Result<ObsData> {
    let version = check_version(path, text, 'O')?;
    let lines: Vec<&str> = text.lines().collect();
    let end = header_end(path, &lines)?;
    let (header, renamed, counts) = normalise_obs_header(path, &lines, end)?;
    if counts.is_empty() {
        return Err(format_err(
            path,
            None,
            "the header has no 'SYS / # / OBS TYPES' lines",
        ));
    }
    if !lines[..end].iter().any(|l| label(l) == "TIME OF FIRST OBS") {
        return Err(format_err(
            path,
            None,
            "the header has no 'TIME OF FIRST OBS' line (RINEX 3 requires it: it names the time system)",
        ));
    }
    let expected = check_obs_body(path, &lines, end, &counts)?;
    // The rinex crate keeps every signal of the file as a map entry (about 80 bytes each: a
    // 35 MB file took 270 MB): it parses the body in chunks of epochs after the (normalised)
    // header, each converted to the compact records here and dropped. The body is the file's
    // own text (joined with plain line ends if it has carriage returns).
    let joined: String;
    let body = if text.contains('\r') {
        joined = lines[end..].iter().flat_map(|l| [*l, "\n"]).collect();
        joined.as_str()
    } else {
        split_header_body(text).1
    };
    drop(lines);
    let header = header.as_str();
    let chunks = epoch_chunks(body, chunk);
    let mut codes: Vec<String> = Vec::new();
    let mut code_ix: HashMap<String, u16> = HashMap::new();
    let mut epochs = Vec::new();
    let mut rnx = None;
    for chunk in chunks
        .iter()
        .copied()
        .chain(chunks.is_empty().then_some(""))
    {
        let mut part = String::with_capacity(header.len() + chunk.len());
        part.push_str(header);
        part.push_str(chunk);
        let r = crate_parse(path, &part)?;
        drop(part);
        convert_obs_records(&r, &mut codes, &mut code_ix, &mut epochs);
        if rnx.is_none() {
            rnx = Some(r.header);
        }
    }
    let Some(rnx) = rnx else {
        return Err(format_err(path, None, "the RINEX parser returned nothing"));
    };
    if epochs.len() != expected {
        return Err(format_err(
            path,
            None,
            format!("{expected} epochs in the file but the RINEX parser returned {}; the file may be malformed", epochs.len()),
        ));
    }
    obs_data(version, codes, epochs, &rnx, renamed)
}

/// Epochs per chunk the rinex crate parses at a time (see [`parse_obs`]).
const OBS_CHUNK_EPOCHS: usize = 200;

/// The text up to and including the `END OF HEADER` line, and the rest.
fn split_header_body(text: &str) -> (&str, &str) {
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        at += line.len();
        if label(line.trim_end_matches(['\r', '\n'])) == "END OF HEADER" {
            return text.split_at(at);
        }
    }
    (text, "")
}

/// The body cut before every `n`-th epoch line (`>`), each piece holding whole records.
fn epoch_chunks(body: &str, n: usize) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut start, mut at, mut seen) = (0, 0, 0usize);
    for line in body.split_inclusive('\n') {
        if line.starts_with('>') {
            if seen > 0 && seen % n == 0 {
                out.push(&body[start..at]);
                start = at;
            }
            seen += 1;
        }
        at += line.len();
    }
    if start < body.len() && !body[start..].trim().is_empty() {
        out.push(&body[start..]);
    }
    out
}

/// Append the crate's observation records (flags 0 and 1) as compact epochs.
fn convert_obs_records(
    rnx: &Rinex,
    codes: &mut Vec<String>,
    code_ix: &mut HashMap<String, u16>,
    epochs: &mut Vec<ObsEpoch>,
) {
    for (key, o) in rnx.observations_iter() {
        let flag = key.flag as u8;
        if flag > 1 {
            continue;
        }
        let time = gpst(&key.epoch, TimeScale::GPST);
        let mut obs = Vec::with_capacity(o.signals.len());
        for s in &o.signals {
            let name = s.observable.to_string();
            if name.starts_with("WZ") {
                continue;
            }
            let Some(sat) = to_sat(&s.sv) else { continue };
            let code = match code_ix.get(&name) {
                Some(&c) => c,
                None => {
                    codes.push(name.clone());
                    let c = (codes.len() - 1) as u16;
                    code_ix.insert(name, c);
                    c
                }
            };
            obs.push(Obs {
                sat,
                code,
                value: s.value,
            });
        }
        epochs.push(ObsEpoch { time, flag, obs });
    }
}

/// The observation data from the converted epochs and the (first chunk's) header.
fn obs_data(
    version: String,
    codes: Vec<String>,
    epochs: Vec<ObsEpoch>,
    header: &rinex::header::Header,
    renamed: HashMap<String, String>,
) -> Result<ObsData> {
    let mut header_codes = BTreeMap::new();
    if let Some(h) = header.obs.as_ref() {
        for (c, v) in &h.codes {
            let letter = format!("{c:x}").chars().next().unwrap_or('?');
            let names: Vec<String> = v
                .iter()
                .map(|o| o.to_string())
                .filter(|n| !n.starts_with("WZ"))
                .collect();
            header_codes.insert(letter, names);
        }
    }
    let mut dropped: Vec<String> = renamed.into_values().collect();
    dropped.sort();
    let approx_position = header
        .rx_position
        .map(|(x, y, z)| Vector3::new(x, y, z))
        .filter(|p| p.norm() > 1.0);
    let receiver = header
        .rcvr
        .as_ref()
        .map(|r| r.model.clone())
        .unwrap_or_default();
    Ok(ObsData {
        version,
        codes,
        header_codes,
        dropped_codes: dropped,
        approx_position,
        receiver,
        epochs,
    })
}

fn orbit(e: &rinex::navigation::Ephemeris, key: &str) -> Option<f64> {
    e.orbits
        .get(key)
        .map(|o| o.as_f64())
        .filter(|v| v.is_finite())
}

/// RTKLIB's URA table (m): a broadcast accuracy is rounded up to the next entry.
const URA: [f64; 15] = [
    2.4, 3.4, 4.85, 6.85, 9.65, 13.65, 24.0, 48.0, 96.0, 192.0, 384.0, 768.0, 1536.0, 3072.0,
    6144.0,
];

fn ura_round_up(v: f64) -> f64 {
    if !(v >= 0.0) {
        return f64::NAN;
    }
    URA.iter().copied().find(|&u| u >= v).unwrap_or(6144.0)
}

/// Read a RINEX 3 navigation file.
pub fn parse_nav(path: &str, text: &str) -> Result<NavData> {
    let version = check_version(path, text, 'N')?;
    let lines: Vec<&str> = text.lines().collect();
    let end = header_end(path, &lines)?;
    let expected = check_nav_body(path, &lines, end)?;
    if expected == 0 {
        return Err(format_err(
            path,
            None,
            "no navigation records after the header",
        ));
    }
    let rnx = crate_parse(path, text)?;
    let klobuchar = rnx
        .header
        .ionod_corrections
        .get(&Constellation::GPS)
        .and_then(|m| m.as_klobuchar())
        .map(|k| {
            [
                k.alpha.0, k.alpha.1, k.alpha.2, k.alpha.3, k.beta.0, k.beta.1, k.beta.2, k.beta.3,
            ]
        });
    let mut ephemerides: BTreeMap<Sat, Vec<Ephemeris>> = BTreeMap::new();
    let mut records: BTreeMap<char, usize> = BTreeMap::new();
    let mut incomplete = 0;
    for (key, e) in rnx.nav_ephemeris_frames_iter() {
        let Some(sat) = to_sat(&key.sv) else { continue };
        *records.entry(sat.letter).or_default() += 1;
        if !Sys::POSITIONING.contains(&sat.sys) {
            continue;
        }
        let scale = if sat.sys == Sys::BeiDou {
            TimeScale::BDT
        } else {
            TimeScale::GPST
        };
        let toc = gpst(&key.epoch, TimeScale::GPST);
        let toc_sys = gpst(&key.epoch, scale);
        let fields = [
            "sqrta", "e", "i0", "omega0", "omega", "m0", "deltaN", "idot", "omegaDot", "cuc",
            "cus", "crc", "crs", "cic", "cis", "toe",
        ];
        let vals: Option<Vec<f64>> = fields.iter().map(|f| orbit(e, f)).collect();
        let Some(v) = vals else {
            incomplete += 1;
            continue;
        };
        // Orbits no GNSS satellite flies (a corrupt record): √A of 1000–10 000 √m (semi-major
        // axis 1 000–100 000 km), eccentricity below 0.9.
        if !(v[0] > 1e3 && v[0] < 1e4 && v[1] >= 0.0 && v[1] < 0.9) {
            incomplete += 1;
            continue;
        }
        let toe_sow = v[15];
        let mut d = toe_sow - toc_sys.sow;
        d -= (d / super::broadcast::WEEK).round() * super::broadcast::WEEK;
        let toe = toc.add(d);
        let fnav = key.msgtype == NavMessageType::FNAV;
        let health = orbit(e, "health").unwrap_or(0.0) as u32;
        let (tgd, unhealthy, accuracy, iod) = match sat.sys {
            Sys::Gps => (
                orbit(e, "tgd").unwrap_or(0.0),
                health != 0,
                ura_round_up(orbit(e, "accuracy").unwrap_or(f64::NAN)),
                orbit(e, "iode").unwrap_or(f64::NAN),
            ),
            Sys::Qzss => (
                orbit(e, "tgd").unwrap_or(0.0),
                health & !1 != 0,
                ura_round_up(orbit(e, "accuracy").unwrap_or(f64::NAN)),
                orbit(e, "iode").unwrap_or(f64::NAN),
            ),
            Sys::Galileo => {
                let (bgd, bits) = if fnav {
                    ("bgdE5aE1", 0x38)
                } else {
                    ("bgdE5bE1", 0x07)
                };
                let sisa = orbit(e, "sisa").unwrap_or(f64::NAN);
                (
                    orbit(e, bgd).unwrap_or(0.0),
                    health & bits != 0,
                    if sisa > 0.0 && sisa < 1e3 {
                        sisa
                    } else {
                        500.0
                    },
                    orbit(e, "iodnav").unwrap_or(f64::NAN),
                )
            }
            Sys::BeiDou => (
                orbit(e, "tgd1b1b3").unwrap_or(0.0),
                health & 1 != 0,
                ura_round_up(orbit(e, "accuracy").unwrap_or(f64::NAN)),
                orbit(e, "aode").unwrap_or(f64::NAN),
            ),
            _ => continue,
        };
        let (a0, a1, a2) = e.sv_clock();
        ephemerides.entry(sat).or_default().push(Ephemeris {
            sat,
            toc,
            toe,
            toe_sow,
            af: [a0, a1, a2],
            sqrt_a: v[0],
            e: v[1],
            i0: v[2],
            omega0: v[3],
            omega: v[4],
            m0: v[5],
            delta_n: v[6],
            idot: v[7],
            omega_dot: v[8],
            harmonics: [v[9], v[10], v[11], v[12], v[13], v[14]],
            tgd,
            health,
            unhealthy,
            accuracy,
            fnav,
            iod,
        });
    }
    let read: usize = records.values().sum();
    if read == 0 {
        return Err(format_err(
            path,
            None,
            format!("{expected} records in the file but the RINEX parser returned no ephemeris"),
        ));
    }
    Ok(NavData {
        version,
        ephemerides,
        klobuchar,
        records,
        incomplete,
    })
}

/// The RINEX major version of a file's first line (`'3'`), if it has one.
fn major(text: &str) -> Option<char> {
    let first = text.lines().next()?;
    if label(first) != "RINEX VERSION / TYPE" {
        return None;
    }
    first.get(..9)?.trim().chars().next()
}

/// Read and parse an observation file from disk (RINEX 3 or 4; RINEX 2.11 through
/// `super::rinex2::obs_to_v3`, errors naming the original lines).
pub fn read_obs(path: &str) -> Result<ObsData> {
    let text = read_text(path)?;
    read_obs_text(path, &text).map_err(|e| {
        // Compact RINEX was expanded: its line numbers are the expanded text's.
        if is_compact_file(path) {
            match e {
                crate::error::Error::Format(m) => crate::error::Error::Format(m.replacen(
                    &format!("{path}, line "),
                    &format!("{path} (expanded from Compact RINEX), line "),
                    1,
                )),
                other => other,
            }
        } else {
            e
        }
    })
}

/// Whether the file at `path` starts as Compact RINEX (Hatanaka), plain or gzipped.
fn is_compact_file(path: &str) -> bool {
    use std::io::Read;
    let Ok(mut r) = crate::memory::open_bounded(path) else {
        return false;
    };
    let mut head = [0u8; 40];
    let n = r.read(&mut head).unwrap_or(0);
    head[..n].windows(13).any(|w| w == b"COMPACT RINEX")
}

fn read_obs_text(path: &str, text: &str) -> Result<ObsData> {
    if major(text) == Some('2') {
        let (v3, map) = super::rinex2::obs_to_v3(path, text)?;
        let mut obs = parse_obs(path, &v3).map_err(|e| remap_line(e, path, &map))?;
        obs.version = text
            .lines()
            .next()
            .unwrap_or("")
            .get(..9)
            .unwrap_or("")
            .trim()
            .to_string();
        return Ok(obs);
    }
    parse_obs(path, text)
}

/// Read and parse a navigation file from disk (RINEX 3; RINEX 4 through
/// `super::rinex_text::rinex4_nav`, RINEX 2 GPS through `super::rinex2::nav_to_v3`;
/// errors name the original file's lines).
pub fn read_nav(path: &str) -> Result<NavData> {
    let text = read_text(path)?;
    let first = text.lines().next().unwrap_or("");
    if major(&text) == Some('2') {
        let (v3, map) = super::rinex2::nav_to_v3(path, &text)?;
        let mut nav = parse_nav(path, &v3).map_err(|e| remap_line(e, path, &map))?;
        nav.version = first.get(..9).unwrap_or("").trim().to_string();
        return Ok(nav);
    }
    if major(&text) == Some('4') {
        let (v3, map, _dropped, klobuchar) = rinex4_nav(path, &text)?;
        let mut nav = parse_nav(path, &v3).map_err(|e| remap_line(e, path, &map))?;
        nav.version = first.get(..9).unwrap_or("").trim().to_string();
        nav.klobuchar = klobuchar;
        return Ok(nav);
    }
    parse_nav(path, &text)
}

/// An error about line `l` of a converted text, about the original's line `map[l − 1]`.
fn remap_line(e: crate::error::Error, path: &str, map: &[usize]) -> crate::error::Error {
    let crate::error::Error::Format(msg) = &e else {
        return e;
    };
    let prefix = format!("{path}, line ");
    let Some(rest) = msg.strip_prefix(&prefix) else {
        return e;
    };
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    match digits
        .parse::<usize>()
        .ok()
        .and_then(|l| map.get(l.wrapping_sub(1)))
    {
        Some(orig) => {
            crate::error::Error::Format(format!("{prefix}{orig}{}", &rest[digits.len()..]))
        }
        None => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    /// The body parsed in chunks of 7 epochs, 200 (the default) or whole gives the same
    /// observations, header data and epoch count (301 epochs, 57 satellites in view).
    #[test]
    fn chunked_observation_parse_equals_the_whole() {
        let path = format!(
            "{}/../../tests/data/rinex/rover.obs.gz",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = read_text(&path).unwrap();
        let whole = parse_obs_in(&path, &text, usize::MAX).unwrap();
        assert_eq!(whole.epochs.len(), 301);
        for n in [7, OBS_CHUNK_EPOCHS, 300, 301] {
            let part = parse_obs_in(&path, &text, n).unwrap();
            assert_eq!(part, whole, "chunks of {n}");
        }
        let crlf = text.replace('\n', "\r\n");
        assert_eq!(
            parse_obs_in(&path, &crlf, 50).unwrap(),
            whole,
            "CRLF line ends"
        );
        assert_eq!(epoch_chunks("", 5).len(), 0);
        let body = "> a\nx\n> b\ny\n> c\n";
        assert_eq!(epoch_chunks(body, 2), vec!["> a\nx\n> b\ny\n", "> c\n"]);
        let (h, b) = split_header_body(
            "x\n                                                            END OF HEADER\n> 1\n",
        );
        assert!(h.ends_with("END OF HEADER\n") && b == "> 1\n");
    }

    /// The bundled RINEX 3 navigation file written as RINEX 4 (a `> EPH` line before each
    /// record, the Klobuchar header lines as a `> ION G01 LNAV` record, a CNAV record and a
    /// system-time record to leave out) reads to the same ephemerides and coefficients.
    #[test]
    fn rinex4_navigation_reads_as_its_rinex3_form() {
        let path = format!(
            "{}/../../tests/data/rinex/base.nav",
            env!("CARGO_MANIFEST_DIR")
        );
        let v3 = read_text(&path).unwrap();
        let lines: Vec<&str> = v3.lines().collect();
        let end = lines
            .iter()
            .position(|l| label(l) == "END OF HEADER")
            .unwrap();
        let mut v4 = String::new();
        let (mut a, mut b) = (String::new(), String::new());
        for (i, l) in lines.iter().enumerate().take(end + 1) {
            match label(l) {
                "IONOSPHERIC CORR" if l.starts_with("GPSA") => a = l[5..53].to_string(),
                "IONOSPHERIC CORR" if l.starts_with("GPSB") => b = l[5..53].to_string(),
                "IONOSPHERIC CORR" => {}
                _ if i == 0 => v4.push_str(&format!("     4.00{}\n", &l[9..])),
                _ => v4.push_str(&format!("{l}\n")),
            }
        }
        let d19 = |f: &str| -> String {
            f.split_whitespace()
                .map(|x| format!("{:>19.12E}", x.parse::<f64>().unwrap()))
                .collect()
        };
        let (da, db) = (d19(&a), d19(&b));
        v4.push_str("> ION G01 LNAV\n");
        v4.push_str(&format!("    2024 06 24 08 00 00{}\n", &da[..57]));
        v4.push_str(&format!("    {}{}\n", &da[57..], &db[..57]));
        v4.push_str(&format!("    {}{:>19.12E}\n", &db[57..], 0.0));
        v4.push_str("> STO G01 LNAV\n    2024 06 24 08 00 00 GPUT                                  UTC(USNO)\n     2.952840000000E+05 9.313225746155E-10 2.664535259100E-15 0.000000000000E+00\n");
        v4.push_str(
            "> EPH G01 CNAV\nG01 2024 06 24 08 00 00 1.0E-04 0.0E+00 0.0E+00\n     1.0E+00\n",
        );
        for l in &lines[end + 1..] {
            if let Some(c) = l.chars().next().filter(char::is_ascii_alphabetic) {
                let kind = match c {
                    'E' => "INAV",
                    'C' => "D1",
                    'R' => "FDMA",
                    _ => "LNAV",
                };
                v4.push_str(&format!("> EPH {} {kind}\n", &l[..3]));
            }
            v4.push_str(&format!("{l}\n"));
        }
        let (conv, map, dropped, klob) = rinex4_nav("x.rnx", &v4).unwrap();
        assert_eq!(dropped, 3);
        assert_eq!(conv.lines().count(), map.len());
        let from4 = parse_nav("x.rnx", &conv).unwrap();
        let from3 = parse_nav(&path, &v3).unwrap();
        assert_eq!(from4.ephemerides, from3.ephemerides);
        let (k4, k3) = (klob.unwrap(), from3.klobuchar.unwrap());
        for (x, y) in k4.iter().zip(&k3) {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1e-30), "{x} vs {y}");
        }
        // An error in the data names the original file's line.
        let bad = v4.replacen("E+00", "E+0x", 40);
        let dir = std::env::temp_dir().join("navfdi_rnx4_test.rnx");
        std::fs::write(&dir, &bad).unwrap();
        let e = read_nav(dir.to_str().unwrap()).unwrap_err().to_string();
        let line: usize = e
            .split("line ")
            .nth(1)
            .and_then(|r| r.split(':').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        assert!(
            bad.lines()
                .nth(line.saturating_sub(1))
                .is_some_and(|l| l.contains("E+0x")),
            "{e}"
        );
    }

    const OBS: &str =
        "     3.04           OBSERVATION DATA    M                   RINEX VERSION / TYPE
G    5 X1  C1C L1C D1C S1C                                  SYS / # / OBS TYPES
  2024     6    24     8    20    0.0000000     GPS         TIME OF FIRST OBS
                                                            END OF HEADER
> 2024 06 24 08 20  0.0000000  0  2
G05          5.000  20590792.555 108205345.409     -1234.500          46.938
G13          6.000  21590792.555 113205345.409      -234.500          48.100
";

    #[test]
    fn x1_is_dropped_and_columns_stay_aligned() {
        let d = parse_obs("t.obs", OBS).unwrap();
        assert_eq!(d.dropped_codes, vec!["G:X1".to_string()]);
        let c1c = d.code_index("C1C").unwrap();
        let s1c = d.code_index("S1C").unwrap();
        let e = &d.epochs[0];
        assert_eq!(e.time, GpsTime::new(2320, 116_400.0));
        let v: Vec<f64> = e
            .obs
            .iter()
            .filter(|o| o.code == c1c)
            .map(|o| o.value)
            .collect();
        assert_eq!(v, vec![20_590_792.555, 21_590_792.555]);
        let s: Vec<f64> = e
            .obs
            .iter()
            .filter(|o| o.code == s1c)
            .map(|o| o.value)
            .collect();
        assert_eq!(s, vec![46.938, 48.1]);
    }

    #[test]
    fn structure_errors_name_the_line() {
        let cut = &OBS[..OBS.rfind("G13").unwrap()];
        let e = parse_obs("t.obs", cut).unwrap_err().to_string();
        assert!(e.contains("t.obs, line 6") && e.contains("1 found"), "{e}");
        let bad = OBS.replace("20590792.555", "2059O792.555");
        let e = parse_obs("t.obs", &bad).unwrap_err().to_string();
        assert!(e.contains("line 6") && e.contains("not a number"), "{e}");
        let no_time = OBS.replace("TIME OF FIRST OBS", "COMMENT          ");
        let e = parse_obs("t.obs", &no_time).unwrap_err().to_string();
        assert!(e.contains("TIME OF FIRST OBS"), "{e}");
        let e = parse_obs("t.obs", &OBS.replace("3.04", "2.11"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'2.11' is not supported"), "{e}");
        let e = parse_obs("t.obs", &OBS.replace("END OF HEADER", "END OF HEADXX"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("END OF HEADER"), "{e}");
        let e = parse_nav("t.nav", OBS).unwrap_err().to_string();
        assert!(
            e.contains("observation file") && e.contains("expected a navigation file"),
            "{e}"
        );
        let extra = OBS.replace("          46.938", "          46.938          12.000");
        let e = parse_obs("t.obs", &extra).unwrap_err().to_string();
        assert!(
            e.contains("6 observation fields") && e.contains("lists 5"),
            "{e}"
        );
    }

    #[test]
    fn gzip_and_missing_files() {
        use std::io::Write;
        let dir = std::env::temp_dir().join(format!("navfdi-rnx-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.obs.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(OBS.as_bytes()).unwrap();
        let bytes = enc.finish().unwrap();
        std::fs::write(&p, &bytes).unwrap();
        let d = read_obs(p.to_str().unwrap()).unwrap();
        assert_eq!(d.epochs.len(), 1);
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        let e = read_obs(p.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("gzip"), "{e}");
        let e = read_obs(dir.join("none.obs").to_str().unwrap()).unwrap_err();
        assert!(matches!(e, Error::Io(_)));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
