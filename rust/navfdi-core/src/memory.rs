//! Memory estimates checked before large allocations.
//!
//! A failed allocation aborts the process (and kills a Jupyter kernel), and on Linux an
//! over-committed one may instead bring the out-of-memory killer. So whole-run functions
//! estimate what they will allocate and refuse, with [`crate::Error::TooLarge`], when it
//! exceeds [`FRACTION`] of the memory available: the message says how much is needed and what
//! to change.
//!
//! The memory available is the smallest of: `MemAvailable` in `/proc/meminfo`, the cgroup v2
//! limit less current use (`/sys/fs/cgroup/memory.max`, `memory.current`), and the
//! environment variable `NAVFDI_MEMORY_LIMIT` (bytes) when set. Where none can be read,
//! [`FALLBACK`] bytes are assumed.

use crate::error::{Error, Result};

/// Share of the available memory one computation may plan to use.
pub const FRACTION: f64 = 0.8;

/// Bytes assumed available where the system does not say (8 GiB).
pub const FALLBACK: f64 = 8.0 * 1024.0 * 1024.0 * 1024.0;

fn read_number(path: &str) -> Option<f64> {
    std::fs::read_to_string(path)
        .ok()?
        .trim()
        .parse::<f64>()
        .ok()
}

fn meminfo_available() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// Bytes of memory available to this process now (see the module documentation).
pub fn available() -> f64 {
    let mut avail: Option<f64> = meminfo_available();
    if let (Some(max), Some(cur)) = (
        read_number("/sys/fs/cgroup/memory.max"),
        read_number("/sys/fs/cgroup/memory.current"),
    ) {
        let free = (max - cur).max(0.0);
        avail = Some(avail.map_or(free, |a| a.min(free)));
    }
    if let Some(limit) = std::env::var("NAVFDI_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| *v > 0.0)
    {
        avail = Some(avail.map_or(limit, |a| a.min(limit)));
    }
    avail.unwrap_or(FALLBACK)
}

/// A byte count for people: `"512 MiB"`, `"3.2 GiB"`, `"8.1e+06 GiB"`.
pub fn human(bytes: f64) -> String {
    const KIB: f64 = 1024.0;
    let (v, unit) = if bytes < KIB * KIB {
        (bytes / KIB, "KiB")
    } else if bytes < KIB * KIB * KIB {
        (bytes / (KIB * KIB), "MiB")
    } else {
        (bytes / (KIB * KIB * KIB), "GiB")
    };
    if v >= 1e5 {
        format!("{v:.1e} {unit}")
    } else if v >= 100.0 {
        format!("{v:.0} {unit}")
    } else {
        format!("{v:.1} {unit}")
    }
}

/// Refuse a computation `what` that needs `bytes` (described by `detail`) when it exceeds
/// [`FRACTION`] of [`available`]; `advice` says which inputs to change.
///
/// Needs of at most [`NEGLIGIBLE`] bytes pass without asking the system (reading
/// `/proc/meminfo` and the cgroup files costs about 20 µs, which per-epoch calls such as
/// `snapshot_fde` must not pay).
pub fn check(what: &str, bytes: f64, detail: &str, advice: &str) -> Result<()> {
    if bytes <= NEGLIGIBLE {
        return Ok(());
    }
    check_against(what, bytes, detail, advice, available())
}

/// Bytes below which [`check`] does not consult the system (256 KiB).
pub const NEGLIGIBLE: f64 = 256.0 * 1024.0;

/// [`check`] against a given number of available bytes.
pub fn check_against(
    what: &str,
    bytes: f64,
    detail: &str,
    advice: &str,
    available: f64,
) -> Result<()> {
    if bytes.is_finite() && bytes <= FRACTION * available {
        return Ok(());
    }
    Err(Error::TooLarge(format!(
        "{what}: needs about {} of memory ({detail}) but at most {} ({:.0} % of the {} available) may be used; {advice}",
        human(bytes),
        human(FRACTION * available),
        FRACTION * 100.0,
        human(available)
    )))
}

/// Largest ratio of decompressed to compressed size [`open_bounded`] accepts (numeric CSV and
/// RINEX compress 3–20×; 300 million blank lines fit in under a megabyte of gzip).
pub const MAX_INFLATION: u64 = 200;

/// A reader that fails once more than `cap` bytes have come through, with an error of `kind`
/// (`InvalidData` for an implausible inflation, `FileTooLarge` for the memory limit) saying
/// `what`.
struct Capped<R> {
    inner: R,
    left: u64,
    what: String,
    kind: std::io::ErrorKind,
}

impl<R: std::io::Read> std::io::Read for Capped<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n as u64 > self.left {
            return Err(std::io::Error::new(self.kind, self.what.clone()));
        }
        self.left -= n as u64;
        Ok(n)
    }
}

/// Open `path` as a byte stream, decompressing gzip (by its magic bytes), bounded: a `.gz` may
/// inflate to [`MAX_INFLATION`] times its size, and nothing beyond the memory limit
/// ([`available`]) is read. `path` must be a regular file (not a device or a pipe, which
/// could stream forever or block).
pub fn open_bounded(path: &str) -> Result<Box<dyn std::io::Read>> {
    use std::io::{BufReader, Read};
    let meta = std::fs::metadata(path).map_err(|e| Error::Io(format!("{path}: {e}")))?;
    if !meta.is_file() {
        return Err(Error::Io(format!(
            "{path}: not a regular file (a directory, device or pipe); give the path of a file"
        )));
    }
    let mut f = std::fs::File::open(path).map_err(|e| Error::Io(format!("{path}: {e}")))?;
    let mut magic = [0u8; 2];
    let got = f
        .read(&mut magic)
        .map_err(|e| Error::Io(format!("{path}: {e}")))?;
    drop(f);
    let f = std::fs::File::open(path).map_err(|e| Error::Io(format!("{path}: {e}")))?;
    let limit = (FRACTION * available()) as u64;
    if got == 2 && magic == [0x1f, 0x8b] {
        let cap = meta.len().saturating_mul(MAX_INFLATION).min(limit);
        Ok(Box::new(Capped {
            inner: flate2::read::MultiGzDecoder::new(BufReader::new(f)),
            left: cap,
            what: format!(
                "{path}: decompresses to more than {} MB ({MAX_INFLATION} times its {} kB): not a plausible log (a compression bomb or a corrupted file)",
                cap / 1_000_000,
                meta.len() / 1000
            ),
            kind: std::io::ErrorKind::InvalidData,
        }))
    } else {
        Ok(Box::new(Capped {
            inner: BufReader::new(f),
            left: limit,
            what: format!(
                "{path}: larger than the {} of memory that may be used",
                human(limit as f64)
            ),
            kind: std::io::ErrorKind::FileTooLarge,
        }))
    }
}

/// The navfdi error of an I/O error `e` while reading `path` through [`open_bounded`]: its
/// caps as [`Error::Format`] (implausible inflation) or [`Error::TooLarge`] (memory), anything
/// else as `other(e)`.
pub fn read_error(e: &std::io::Error, other: impl FnOnce(&std::io::Error) -> Error) -> Error {
    match (e.kind(), e.get_ref()) {
        (std::io::ErrorKind::InvalidData, Some(inner))
            if inner.to_string().contains("decompresses to more than") =>
        {
            Error::Format(inner.to_string())
        }
        (std::io::ErrorKind::FileTooLarge, Some(inner)) => Error::TooLarge(inner.to_string()),
        _ => other(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_beyond_the_fraction() {
        let gib = 1024.0 * 1024.0 * 1024.0;
        assert!(check_against("x", 0.5 * gib, "d", "a", gib).is_ok());
        let e = check_against("run", 2.0 * gib, "1000 epochs", "reduce duration", gib)
            .unwrap_err()
            .to_string();
        assert!(e.contains("2.0 GiB") && e.contains("1.0 GiB") && e.contains("reduce duration"));
        assert!(check_against("x", f64::INFINITY, "d", "a", gib).is_err());
        assert_eq!(human(8e15 * gib), "8.0e15 GiB");
        assert!(available() > 0.0);
        // Small needs pass without consulting the system; NaN or huge ones never do.
        assert!(check("x", NEGLIGIBLE, "d", "a").is_ok());
        assert!(check("x", f64::NAN, "d", "a").is_err());
        assert!(check("x", 1e30, "d", "a").is_err());
    }
}
