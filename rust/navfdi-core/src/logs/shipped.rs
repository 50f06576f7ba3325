//! A prepared recorded-data source as bytes, to run it in another process (a Dask worker)
//! without reading and preparing its logs again: the scenario it was prepared for (JSON), its
//! time 0, the fault-free datum of its protection-level scoring once computed, and the
//! [`LoggedSource`] itself (IMU samples, GNSS streams or satellite ranges, reference).
//!
//! Layout: the 8-byte magic `NAVFDISR`, the navfdi version that wrote it (a length-prefixed
//! UTF-8 string) and the fields in [postcard](https://docs.rs/postcard) encoding (floats as
//! their IEEE-754 bytes, so a decoded source runs bit-identically). A source written by
//! another navfdi version is refused with both versions named: the layout of the prepared
//! streams is not a stable format (files are the stable input, not these bytes).

use super::LoggedSource;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// First bytes of every encoded source.
pub const MAGIC: &[u8; 8] = b"NAVFDISR";

/// The version written into, and required of, encoded sources.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A decoded source and what came with it.
#[derive(Debug, Clone, Deserialize)]
pub struct Shipped {
    /// The scenario the source was prepared for (JSON of [`crate::spec::ScenarioSpec`]).
    pub spec_json: String,
    /// GPS seconds of the run's time 0 (0 for a source whose times were already relative).
    pub time0: f64,
    /// The fault-free datum (east, north, up, m) when it was computed before encoding
    /// (`Some(None)`: computed, none applies; `None`: not computed).
    pub datum: Option<Option<[f64; 3]>>,
    /// The prepared streams.
    pub source: LoggedSource,
}

#[derive(Serialize)]
struct ShippedRef<'a> {
    spec_json: &'a str,
    time0: f64,
    datum: Option<Option<[f64; 3]>>,
    source: &'a LoggedSource,
}

/// Encode a prepared source (see the module docs for the layout).
pub fn encode(
    spec_json: &str,
    time0: f64,
    datum: Option<Option<[f64; 3]>>,
    source: &LoggedSource,
) -> Result<Vec<u8>> {
    let mut out = MAGIC.to_vec();
    out.extend((VERSION.len() as u32).to_le_bytes());
    out.extend(VERSION.as_bytes());
    let body = postcard::to_stdvec(&ShippedRef {
        spec_json,
        time0,
        datum,
        source,
    })
    .map_err(|e| Error::Invalid(format!("prepared source: cannot encode it ({e})")))?;
    out.extend(body);
    Ok(out)
}

/// Decode bytes written by [`encode`]; an error names what is wrong (not a prepared source,
/// another navfdi version, truncated or corrupted).
pub fn decode(bytes: &[u8]) -> Result<Shipped> {
    let bad = |what: &str| Error::Format(format!("prepared source: {what}"));
    let rest = bytes
        .strip_prefix(MAGIC.as_slice())
        .ok_or_else(|| bad("not a navfdi prepared source (its first bytes are not NAVFDISR)"))?;
    if rest.len() < 4 {
        return Err(bad("truncated after its first 8 bytes"));
    }
    let n = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
    let version = rest
        .get(4..4 + n)
        .and_then(|v| std::str::from_utf8(v).ok())
        .ok_or_else(|| bad("truncated or corrupted version field"))?;
    if version != VERSION {
        return Err(bad(&format!(
            "written by navfdi {version}, and this is navfdi {VERSION}: install the same version everywhere the campaign runs"
        )));
    }
    let (shipped, left): (Shipped, &[u8]) = postcard::take_from_bytes(&rest[4 + n..])
        .map_err(|e| bad(&format!("truncated or corrupted ({e})")))?;
    if !left.is_empty() {
        return Err(bad(&format!(
            "{} bytes after the end of the source: corrupted",
            left.len()
        )));
    }
    Ok(shipped)
}
