//! IMU logs in CSV (plain or gzip): one streaming pass from the file to the samples, with the
//! column mapping, units and checks a scenario's `[source.imu]` names, and errors that name the
//! file, line and column.
//!
//! The file is read through a bounded decompressor ([`open_bounded`]): a `.gz` that inflates
//! beyond [`crate::memory::MAX_INFLATION`] times its own size (a compression bomb: 300 million blank lines fit in
//! under a megabyte) or beyond the memory limit is refused before it is held. Memory is
//! bounded by the samples kept (7 floats per row), not by the file. A UTF-8 byte-order mark is
//! skipped; blank lines are skipped and do not shift the line numbers reported.

use crate::error::{Error, Result};
use crate::memory::open_bounded;

/// Largest angular rate accepted (rad/s, about 5 700 deg/s: above any MEMS or tactical range).
pub const MAX_RATE: f64 = 100.0;
/// Largest specific force accepted (m/s², about 100 g).
pub const MAX_SPECIFIC_FORCE: f64 = 1000.0;
/// Largest median angular rate accepted (rad/s): a log whose median rate is above 57 deg/s
/// holds deg/s read as rad/s.
pub const MAX_MEDIAN_RATE: f64 = 1.0;
/// The median specific force's range accepted (m/s²): at rest it is about 9.8; outside,
/// the units are wrong (g read as m/s²) or gravity was removed.
pub const MEDIAN_SPECIFIC_FORCE: (f64, f64) = (2.0, 50.0);

/// Which columns hold the time.
#[derive(Debug, Clone, PartialEq)]
pub enum TimeColumns {
    /// GPS week and seconds of week.
    WeekSeconds(String, String),
    /// One time column in units of [`ImuCsvSpec::time_unit`] (GPS seconds since the GPS epoch,
    /// 1980-01-06, or another count the caller converts, e.g. Unix time).
    Seconds(String),
}

/// How the fields of a line are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delimiter {
    /// One byte (`b','`, `b';'`, `b'\t'`, `b' '`, …).
    Byte(u8),
    /// Runs of spaces and tabs, leading and trailing ones ignored (column-aligned text, as
    /// KF-GINS's IMU files are written).
    Whitespace,
}

/// A reader that turns runs of spaces and tabs into one space and drops them at the start and
/// end of each line, newlines kept (so line numbers stay the file's): whitespace-separated
/// text as single-space-separated for the CSV reader.
struct Squeeze<R> {
    inner: R,
    buf: Vec<u8>,
    pos: usize,
    /// A space is owed before the next field (a run seen after a field on this line).
    pending: bool,
    /// At the start of a line (no field yet).
    start: bool,
}

impl<R: std::io::Read> std::io::Read for Squeeze<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let mut n = 0;
        while n < out.len() {
            if self.pos == self.buf.len() {
                self.buf.resize(1 << 16, 0);
                let got = self.inner.read(&mut self.buf)?;
                self.buf.truncate(got);
                self.pos = 0;
                if got == 0 {
                    break;
                }
            }
            let b = self.buf[self.pos];
            match b {
                b' ' | b'\t' => {
                    self.pos += 1;
                    self.pending = !self.start;
                }
                b'\n' | b'\r' => {
                    out[n] = b;
                    n += 1;
                    self.pos += 1;
                    self.pending = false;
                    self.start = true;
                }
                _ if self.pending => {
                    out[n] = b' ';
                    n += 1;
                    self.pending = false;
                }
                _ => {
                    out[n] = b;
                    n += 1;
                    self.pos += 1;
                    self.start = false;
                }
            }
        }
        Ok(n)
    }
}

/// How to read an IMU CSV log.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuCsvSpec {
    /// Time columns.
    pub time: TimeColumns,
    /// Angular rate (or angle increment) columns x, y, z.
    pub gyro: [String; 3],
    /// Specific force (or velocity increment) columns x, y, z.
    pub accel: [String; 3],
    /// Factor to rad/s (rad for increments).
    pub gyro_scale: f64,
    /// Factor to m/s² (m/s for increments).
    pub accel_scale: f64,
    /// The columns hold per-sample increments (divided by the sample interval).
    pub increments: bool,
    /// Largest interval between samples accepted (s).
    pub max_gap: f64,
    /// Seconds per unit of a single time column (1; 1e-3 for milliseconds, 1e-9 for
    /// nanoseconds); week and seconds of week are in seconds.
    pub time_unit: f64,
    /// The first line names the columns; false: every line is a sample and the columns are
    /// named by their position, `"1"`, `"2"`, … (from 1).
    pub header: bool,
    /// The field separator.
    pub delimiter: Delimiter,
    /// Names of the unit fields, for messages (e.g. `source.imu.gyro_unit`).
    pub unit_fields: [String; 2],
    /// Samples that share a time stamp (a logger stamping them in batches) are spread evenly
    /// from it to the next stamp (the last batch at the log's median interval); false: a
    /// time that does not increase is refused.
    pub spread_times: bool,
}

/// An IMU log as read: times (GPS s), rates (rad/s) and specific forces (m/s²) in the IMU's
/// axes, one row per sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuTable {
    /// Sample times (GPS seconds since the GPS epoch), strictly increasing.
    pub t: Vec<f64>,
    /// Angular rate per sample (rad/s).
    pub gyro: Vec<[f64; 3]>,
    /// Specific force per sample (m/s²).
    pub accel: Vec<[f64; 3]>,
    /// Rows left out as repeats: a row identical to the one before it in time and every
    /// value (a logger writing a sample twice).
    pub repeated: usize,
    /// Line of the first repeat (0: none).
    pub first_repeated_line: u64,
    /// Rows left out as placeholders: a specific force (or velocity increment) of exactly
    /// zero on all three axes, which no IMU near the Earth measures (free fall) and loggers
    /// write for a sample they did not get. The interval it leaves is a gap like any other.
    pub zeroed: usize,
    /// Line of the first placeholder (0: none).
    pub first_zeroed_line: u64,
    /// Samples whose shared time stamp was spread ([`ImuCsvSpec::spread_times`]).
    pub spread: usize,
    /// The time column holds ISO 8601 date-times (`2025-07-08T19:34:43.123`, a space for the
    /// `T` and a trailing `Z` accepted), told from its first row: `t` is then calendar
    /// seconds since 1980-01-06 00:00:00 as written, no leap seconds applied (the caller
    /// knows the time scale).
    pub iso: bool,
}

/// An error at a cell: "`path`, line `l`, column '`col`': `msg`" (without a line when it is 0).
fn cell_err(path: &str, line: u64, col: &str, msg: impl std::fmt::Display) -> Error {
    if line > 0 {
        Error::Format(format!("{path}, line {line}, column '{col}': {msg}"))
    } else {
        Error::Format(format!("{path}, column '{col}': {msg}"))
    }
}

fn format_err(path: &str, line: Option<u64>, msg: impl std::fmt::Display) -> Error {
    match line {
        Some(l) => Error::Format(format!("{path}, line {l}: {msg}")),
        None => Error::Format(format!("{path}: {msg}")),
    }
}

/// Read an IMU CSV log (header line, then one sample per row) as `spec` says. Errors name the
/// file, the line and the column: a missing column (with the header's), a row with another
/// number of fields (a trailing comma says so), a value that is not a finite number, time not
/// increasing (a row repeating the one before it exactly is left out and counted instead, as
/// is a row whose specific force is exactly zero on every axis: a placeholder), a
/// gap over `max_gap`, a sample beyond [`MAX_RATE`] or [`MAX_SPECIFIC_FORCE`], a median
/// specific force far from gravity or a median rate over [`MAX_MEDIAN_RATE`] (units), a file
/// with no sample.
pub fn read_imu_csv(path: &str, spec: &ImuCsvSpec) -> Result<ImuTable> {
    if !(spec.max_gap > 0.0 && spec.max_gap.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "source.imu.max_gap".into(),
            value: spec.max_gap,
            requirement: "must be a positive number of seconds".into(),
        });
    }
    for (name, v) in [
        (&spec.unit_fields[0], spec.gyro_scale),
        (&spec.unit_fields[1], spec.accel_scale),
    ] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::InvalidParameter {
                name: name.clone(),
                value: v,
                requirement: "unit factor must be positive".into(),
            });
        }
    }
    let mut reader = open_bounded(path)?;
    let delimiter = match spec.delimiter {
        Delimiter::Byte(b) => b,
        Delimiter::Whitespace => {
            reader = Box::new(Squeeze {
                inner: reader,
                buf: Vec::new(),
                pos: 0,
                pending: false,
                start: true,
            });
            b' '
        }
    };
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(spec.header)
        .delimiter(delimiter)
        .flexible(true)
        .trim(csv::Trim::Headers)
        .from_reader(reader);
    let io = |e: csv::Error| -> Error {
        let line = e.position().map(|p| p.line());
        match e.kind() {
            csv::ErrorKind::Io(io) => {
                crate::memory::read_error(io, |io| Error::Io(format!("{path}: {io}")))
            }
            csv::ErrorKind::Utf8 { .. } => format_err(path, line, "not UTF-8 text"),
            _ => format_err(path, line, e),
        }
    };
    let first: Vec<String> = rdr
        .headers()
        .map_err(io)?
        .iter()
        .map(|h| h.trim_start_matches('\u{feff}').trim().to_string())
        .collect();
    if first.iter().all(|h| h.is_empty()) {
        let what = if spec.header {
            "a header line naming the columns is expected"
        } else {
            "no samples"
        };
        return Err(format_err(path, Some(1), format!("empty file: {what}")));
    }
    // Without a header the columns are named by their position (from 1), and the first line
    // (read again below as a record) is a sample.
    let header: Vec<String> = if spec.header {
        first
    } else {
        (1..=first.len()).map(|k| k.to_string()).collect()
    };
    let col = |name: &str| -> Result<usize> {
        header.iter().position(|h| h == name).ok_or_else(|| {
            let has = if spec.header {
                format!("the header has {}", header.join(", "))
            } else {
                format!(
                    "the first line has {} columns, numbered from 1",
                    header.len()
                )
            };
            format_err(path, Some(1), format!("no column '{name}' ({has})"))
        })
    };
    let tcols: Vec<usize> = match &spec.time {
        TimeColumns::WeekSeconds(w, s) => vec![col(w)?, col(s)?],
        TimeColumns::Seconds(s) => vec![col(s)?],
    };
    let g = [
        col(&spec.gyro[0])?,
        col(&spec.gyro[1])?,
        col(&spec.gyro[2])?,
    ];
    let a = [
        col(&spec.accel[0])?,
        col(&spec.accel[1])?,
        col(&spec.accel[2])?,
    ];
    let width = header.len();
    let mut out = ImuTable::default();
    let mut last_raw = ([f64::NAN; 3], [f64::NAN; 3]);
    let mut first_row = true;
    // Byte records: only the seven cells read are trimmed and decoded (the rest of a row is
    // neither validated as UTF-8 nor trimmed), which halves the time per row.
    let mut rec = csv::ByteRecord::new();
    let mut last_line = 1u64;
    let check_every = 1 << 16;
    loop {
        match rdr.read_byte_record(&mut rec) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(io(e)),
        }
        let line = rec.position().map_or(last_line + 1, |p| p.line());
        last_line = line;
        if rec.len() == 1 && rec.get(0).is_some_and(|f| f.is_empty()) {
            continue;
        }
        if rec.len() != width {
            let hint = if rec.len() == width + 1 && rec.get(width).is_some_and(|f| f.is_empty()) {
                " (a trailing comma?)"
            } else {
                ""
            };
            let first = if spec.header {
                "the header"
            } else {
                "the first line"
            };
            return Err(format_err(
                path,
                Some(line),
                format!("{} fields, {first} has {width}{hint}", rec.len()),
            ));
        }
        let num = |c: usize| -> Result<f64> {
            let raw = rec.get(c).unwrap_or(b"").trim_ascii();
            match std::str::from_utf8(raw).map(str::parse::<f64>) {
                Ok(Ok(v)) if v.is_finite() => Ok(v),
                _ => Err(cell_err(
                    path,
                    line,
                    &header[c],
                    format!(
                        "'{}' is {}",
                        String::from_utf8_lossy(raw),
                        if raw.is_empty() {
                            "missing"
                        } else {
                            "not a finite number"
                        }
                    ),
                )),
            }
        };
        if first_row {
            // A single time column holds ISO date-times if the first data row's does.
            first_row = false;
            if let (Some(&s), None) = (tcols.first(), tcols.get(1)) {
                out.iso = iso_seconds(rec.get(s).unwrap_or(b"").trim_ascii()).is_some();
            }
        }
        let t = match (tcols.first(), tcols.get(1)) {
            (Some(&w), Some(&s)) => num(w)? * 604_800.0 + num(s)?,
            (Some(&s), None) if out.iso => match iso_seconds(rec.get(s).unwrap_or(b"").trim_ascii()) {
                Some(v) => v,
                None => {
                    return Err(cell_err(
                        path,
                        line,
                        &header[s],
                        format!(
                            "'{}' is not an ISO date-time (YYYY-MM-DDThh:mm:ss[.fff]) as the first row's is",
                            String::from_utf8_lossy(rec.get(s).unwrap_or(b""))
                        ),
                    ))
                }
            },
            (Some(&s), None) => num(s)? * spec.time_unit,
            _ => return Err(format_err(path, Some(line), "no time column")),
        };
        let gv = [num(g[0])?, num(g[1])?, num(g[2])?];
        let av = [num(a[0])?, num(a[1])?, num(a[2])?];
        if av == [0.0; 3] {
            out.zeroed += 1;
            if out.first_zeroed_line == 0 {
                out.first_zeroed_line = line;
            }
            continue;
        }
        if let Some(&prev) = out.t.last() {
            let tname = tcols.last().map_or("time", |&c| header[c].as_str());
            if t == prev && !spec.spread_times && last_raw == (gv, av) {
                // The same sample written twice: nothing is lost by leaving it out (in a
                // batch sharing one stamp, two equal samples are two samples).
                out.repeated += 1;
                if out.first_repeated_line == 0 {
                    out.first_repeated_line = line;
                }
                continue;
            }
            if t == prev && spec.spread_times {
                out.spread += 1;
            } else if !(t > prev) {
                let hint = if t == prev {
                    "; if the logger stamps its samples in batches, source.imu.time_repeats = \"spread\" spreads each batch to the next stamp"
                } else {
                    ""
                };
                return Err(cell_err(
                    path,
                    line,
                    tname,
                    format!("time does not increase ({t:.6} s after {prev:.6} s){hint}"),
                ));
            }
            if t - prev > spec.max_gap {
                return Err(cell_err(
                    path,
                    line,
                    tname,
                    format!(
                        "a gap of {:.3} s in the IMU log exceeds source.imu.max_gap = {} s",
                        t - prev,
                        spec.max_gap
                    ),
                ));
            }
        }
        last_raw = (gv, av);
        out.t.push(t);
        out.gyro.push(gv.map(|v| v * spec.gyro_scale));
        out.accel.push(av.map(|v| v * spec.accel_scale));
        if out.t.len() % check_every == 0 {
            crate::memory::check(
                "reading the IMU log",
                (out.t.len() * 7 * 8) as f64 * 2.0,
                &format!("{} samples so far", out.t.len()),
                "give a shorter log",
            )?;
        }
        // Plausibility of this row (after units and increments are known, below for
        // increments): rates and forces beyond any IMU's range name their cell.
        if !spec.increments {
            plausible(
                path,
                line,
                &header,
                &g,
                &a,
                out.gyro.last(),
                out.accel.last(),
            )?;
        }
    }
    if out.t.is_empty() {
        return Err(format_err(path, None, "no samples (only a header line)"));
    }
    if out.spread > 0 {
        spread_batches(&mut out.t);
    }
    if spec.increments {
        let n = out.t.len();
        for k in 0..n {
            let dt = if k == 0 {
                if n > 1 {
                    out.t[1] - out.t[0]
                } else {
                    f64::NAN
                }
            } else {
                out.t[k] - out.t[k - 1]
            };
            if !(dt > 0.0) {
                return Err(format_err(
                    path,
                    None,
                    "increments need at least two samples",
                ));
            }
            out.gyro[k] = out.gyro[k].map(|v| v / dt);
            out.accel[k] = out.accel[k].map(|v| v / dt);
            plausible(
                path,
                0,
                &header,
                &g,
                &a,
                Some(&out.gyro[k]),
                Some(&out.accel[k]),
            )?;
        }
    }
    let mut mags: Vec<f64> = out
        .accel
        .iter()
        .map(|f| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt())
        .collect();
    let mid = mags.len() / 2;
    let med = *mags.select_nth_unstable_by(mid, f64::total_cmp).1;
    if !(MEDIAN_SPECIFIC_FORCE.0..=MEDIAN_SPECIFIC_FORCE.1).contains(&med) {
        return Err(format_err(
            path,
            None,
            format!(
                "median specific force {} m/s² after the unit conversion; at rest it is about 9.8: check {}",
                g3(med),
                spec.unit_fields[1]
            ),
        ));
    }
    let mut rates: Vec<f64> = out
        .gyro
        .iter()
        .map(|w| (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt())
        .collect();
    let med = *rates.select_nth_unstable_by(mid, f64::total_cmp).1;
    if med > MAX_MEDIAN_RATE {
        return Err(format_err(
            path,
            None,
            format!(
                "median angular rate {med:.3} rad/s ({:.0} deg/s) after the unit conversion: no vehicle turns that fast most of the time; check {} (deg/s read as rad/s?)",
                med.to_degrees(),
                spec.unit_fields[0]
            ),
        ));
    }
    Ok(out)
}

/// `v` with three significant digits and no trailing zeros (`1`, `9.81`, `1.5e+03`).
fn g3(v: f64) -> String {
    if !(v.abs() >= 1e-3 && v.abs() < 1e4) {
        return format!("{v:.2e}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A sample beyond any IMU's range is an error naming its line (0: unknown) and column.
fn plausible(
    path: &str,
    line: u64,
    header: &[String],
    g: &[usize; 3],
    a: &[usize; 3],
    gyro: Option<&[f64; 3]>,
    accel: Option<&[f64; 3]>,
) -> Result<()> {
    for (j, v) in gyro.into_iter().flatten().enumerate() {
        if v.abs() > MAX_RATE {
            return Err(cell_err(
                path,
                line,
                &header[g[j]],
                format!("angular rate {v:.4e} rad/s is beyond any IMU's range ({MAX_RATE} rad/s); check the value and the unit"),
            ));
        }
    }
    for (j, v) in accel.into_iter().flatten().enumerate() {
        if v.abs() > MAX_SPECIFIC_FORCE {
            return Err(cell_err(
                path,
                line,
                &header[a[j]],
                format!("specific force {v:.4e} m/s² is beyond any IMU's range ({MAX_SPECIFIC_FORCE} m/s²); check the value and the unit"),
            ));
        }
    }
    Ok(())
}

/// Calendar seconds since 1980-01-06 00:00:00 of an ISO 8601 date-time
/// `YYYY-MM-DD[T ]hh:mm:ss[.fff][Z]` as written (no leap seconds), or None.
pub fn iso_seconds(raw: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(raw).ok()?.trim();
    let s = s.strip_suffix('Z').unwrap_or(s);
    if s.len() < 19 || !s.is_char_boundary(10) || !s.is_char_boundary(11) {
        return None;
    }
    let (date, time) = (&s[..10], &s[11..]);
    if !matches!(s.as_bytes()[10], b'T' | b' ') {
        return None;
    }
    let d: Vec<&str> = date.split('-').collect();
    let hms: Vec<&str> = time.split(':').collect();
    if d.len() != 3 || hms.len() != 3 || d[0].len() != 4 || d[1].len() != 2 || d[2].len() != 2 {
        return None;
    }
    let digits = |x: &str| !x.is_empty() && x.bytes().all(|b| b.is_ascii_digit());
    if !(d.iter().all(|x| digits(x)) && digits(hms[0]) && digits(hms[1])) {
        return None;
    }
    let (y, m, day): (i64, i64, i64) = (d[0].parse().ok()?, d[1].parse().ok()?, d[2].parse().ok()?);
    let (hh, mm): (i64, i64) = (hms[0].parse().ok()?, hms[1].parse().ok()?);
    let sec: f64 = if hms[2].bytes().all(|b| b.is_ascii_digit() || b == b'.') {
        hms[2].parse().ok()?
    } else {
        return None;
    };
    if !((1..=12).contains(&m) && (1..=31).contains(&day) && hh < 24 && mm < 60 && sec < 61.0) {
        return None;
    }
    // Days from the civil date (proleptic Gregorian), then from 1980-01-06.
    let (yy, mp) = if m <= 2 { (y - 1, m + 9) } else { (y, m - 3) };
    let era = yy.div_euclid(400);
    let yoe = yy - era * 400;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146_097 + doe - 719_468 - 3_657;
    Some(days as f64 * 86_400.0 + (hh * 3600 + mm * 60) as f64 + sec)
}

/// Times `t` (increasing, runs of equal stamps allowed) with each run spread evenly from its
/// stamp to the next one; the last run at the median interval between distinct stamps per
/// sample.
fn spread_batches(t: &mut [f64]) {
    let n = t.len();
    let mut per: Vec<f64> = Vec::new();
    let mut a = 0;
    while a < n {
        let mut b = a + 1;
        while b < n && t[b] == t[a] {
            b += 1;
        }
        if b < n {
            let step = (t[b] - t[a]) / (b - a) as f64;
            per.push(step);
            for j in 1..b - a {
                t[a + j] = t[a] + j as f64 * step;
            }
        } else if b - a > 1 {
            let step = if per.is_empty() {
                f64::NAN
            } else {
                crate::stats::median_of(&mut per.clone())
            };
            for j in 1..b - a {
                t[a + j] = t[a] + j as f64 * step;
            }
        }
        a = b;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn whitespace_runs_become_one_separator_and_lines_stay() {
        use std::io::Read;
        let text = b"  t   gx\tgy \n\n 1.5  2 \t 3  \r\n4 5 6";
        let mut s = Squeeze {
            inner: &text[..],
            buf: Vec::new(),
            pos: 0,
            pending: false,
            start: true,
        };
        let mut out = String::new();
        s.read_to_string(&mut out).unwrap();
        assert_eq!(out, "t gx gy\n\n1.5 2 3\r\n4 5 6");
    }

    fn spec() -> ImuCsvSpec {
        ImuCsvSpec {
            time: TimeColumns::Seconds("t".into()),
            gyro: ["gx".into(), "gy".into(), "gz".into()],
            accel: ["ax".into(), "ay".into(), "az".into()],
            gyro_scale: 1.0,
            accel_scale: 1.0,
            increments: false,
            max_gap: 0.1,
            time_unit: 1.0,
            header: true,
            delimiter: Delimiter::Byte(b','),
            unit_fields: ["gyro_unit".into(), "accel_unit".into()],
            spread_times: false,
        }
    }

    fn write(dir: &std::path::Path, name: &str, text: &str) -> String {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    }

    fn rows(n: usize) -> String {
        let mut s = String::from("t,gx,gy,gz,ax,ay,az\n");
        for k in 0..n {
            s.push_str(&format!("{},0.01,0,0,0,0,-9.8\n", 1000.0 + k as f64 * 0.01));
        }
        s
    }

    #[test]
    fn reads_bom_blank_lines_and_reports_true_lines() {
        let d = std::env::temp_dir().join(format!("navfdi_imu_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let text = format!("\u{feff}{}", rows(5)).replace("\n1000.02", "\n\n\n1000.02");
        let p = write(&d, "a.csv", &text);
        let t = read_imu_csv(&p, &spec()).unwrap();
        assert_eq!(t.t.len(), 5);
        let bad = text.replace("1000.03,0.01", "1000.03,abc");
        let e = read_imu_csv(&write(&d, "b.csv", &bad), &spec())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 7") && e.contains("'gx'") && e.contains("abc"),
            "{e}"
        );
        let trailing = rows(3).replace("-9.8\n1000.01", "-9.8,\n1000.01");
        let e = read_imu_csv(&write(&d, "c.csv", &trailing), &spec())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2") && e.contains("trailing comma"), "{e}");
        let e = read_imu_csv(&write(&d, "h.csv", "t,gx,gy,gz,ax,ay,az\n"), &spec())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no samples"), "{e}");
        let huge = rows(3).replace("1000.01,0.01", "1000.01,1e300");
        let e = read_imu_csv(&write(&d, "u.csv", &huge), &spec())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("beyond any IMU"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    /// A row written twice is left out and counted; the same time with other values is
    /// still refused.
    #[test]
    fn an_exact_repeat_is_left_out_and_counted() {
        let d = std::env::temp_dir().join(format!("navfdi_rep_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let text = rows(6);
        let line = "1000.02,0.01,0,0,0,0,-9.8\n";
        let twice = text.replacen(line, &format!("{line}{line}{line}"), 1);
        let t = read_imu_csv(&write(&d, "r.csv", &twice), &spec()).unwrap();
        assert_eq!(t.t.len(), 6);
        assert_eq!((t.repeated, t.first_repeated_line), (2, 5));
        let clean = read_imu_csv(&write(&d, "c.csv", &text), &spec()).unwrap();
        assert_eq!((clean.repeated, clean.first_repeated_line), (0, 0));
        assert_eq!((clean.zeroed, t.zeroed), (0, 0));
        // A placeholder row (specific force 0, 0, 0) is left out and counted.
        let hole = text.replacen(line, "1000.02,0,0,0,0,0,0\n", 1);
        let z = read_imu_csv(&write(&d, "z.csv", &hole), &spec()).unwrap();
        assert_eq!((z.t.len(), z.zeroed, z.first_zeroed_line), (5, 1, 4));
        assert!(!z.t.contains(&1000.02));
        assert_eq!(clean.t, t.t);
        let other = text.replacen(line, &format!("{line}1000.02,0.02,0,0,0,0,-9.8\n"), 1);
        let e = read_imu_csv(&write(&d, "o.csv", &other), &spec())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 5") && e.contains("does not increase"),
            "{e}"
        );
        assert!(e.contains("time_repeats"), "{e}");
        // ISO date-times, told from the first row.
        let iso = "t,gx,gy,gz,ax,ay,az\n2025-07-08T19:34:43.50Z,0,0,0,0,0,-9.8\n2025-07-08 19:34:43.51,0,0,0,0,0,-9.8\n";
        let t = read_imu_csv(&write(&d, "i.csv", iso), &spec()).unwrap();
        assert!(t.iso);
        // 2025-07-08 is 16 620 days after 1980-01-06.
        let want = 16_620.0 * 86_400.0 + 19.0 * 3600.0 + 34.0 * 60.0 + 43.5;
        assert!(
            (t.t[0] - want).abs() < 1e-6 && (t.t[1] - want - 0.01).abs() < 1e-6,
            "{:?}",
            t.t
        );
        let e = read_imu_csv(
            &write(&d, "j.csv", &iso.replace("2025-07-08 19", "1436038")),
            &spec(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("line 3") && e.contains("not an ISO date-time"),
            "{e}"
        );
        assert_eq!(iso_seconds(b"1980-01-06T00:00:00"), Some(0.0));
        assert_eq!(
            iso_seconds(b"2024-02-29T12:00:00"),
            Some((16_125.0 + 0.5) * 86_400.0)
        );
        assert!(
            iso_seconds(b"1436038661.9").is_none() && iso_seconds(b"2025-13-01T00:00:00").is_none()
        );
        // Stamped in batches of four at 0.04 s: spread to 0.01 s when asked.
        let mut batched = String::from("t,gx,gy,gz,ax,ay,az\n");
        for k in 0..12 {
            let stamp = 1000.0 + (k / 4) as f64 * 0.04;
            batched.push_str(&format!("{stamp},0.01,{},0,0,0,-9.8\n", k as f64 * 1e-3));
        }
        let p = write(&d, "b.csv", &batched);
        assert!(read_imu_csv(&p, &spec()).is_err());
        let t = read_imu_csv(
            &p,
            &ImuCsvSpec {
                spread_times: true,
                ..spec()
            },
        )
        .unwrap();
        assert_eq!(t.spread, 9);
        for (k, tk) in t.t.iter().enumerate() {
            assert!((tk - (1000.0 + k as f64 * 0.01)).abs() < 1e-9, "{k} {tk}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_compression_bomb_is_refused_without_inflating_it() {
        let d = std::env::temp_dir().join(format!("navfdi_bomb_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("bomb.csv.gz");
        let f = std::fs::File::create(&p).unwrap();
        let mut gz = flate2::write::GzEncoder::new(f, flate2::Compression::best());
        gz.write_all(rows(2).as_bytes()).unwrap();
        let blank = vec![b'\n'; 1 << 20];
        for _ in 0..64 {
            gz.write_all(&blank).unwrap();
        }
        gz.finish().unwrap();
        let e = read_imu_csv(&p.to_string_lossy(), &spec())
            .unwrap_err()
            .to_string();
        assert!(e.contains("decompresses to more than"), "{e}");
        let e = read_imu_csv("/dev/zero", &spec()).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }
}
