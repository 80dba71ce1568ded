//! What to record and how: `--record PATH` / `-p record:=PATH` and the `-p record_*`
//! parameters as [`RecordOptions`].

use fcc_ros::params::parse_bool;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

/// Recording options (`--record PATH`, `-p record:=PATH`, `-p record_*`).
#[derive(Clone, Debug)]
pub struct RecordOptions {
    pub path: PathBuf,
    /// zstd chunk compression (`-p record_compression:=zstd|none`, default zstd).
    pub zstd: bool,
    /// Close the open chunk at least this often (crash-safety bound).
    pub chunk_interval: Duration,
    /// ... or when it holds this many bytes.
    pub chunk_bytes: u64,
    /// Start a new file when a message's log time reaches the file's first log time + this.
    pub split_s: Option<f64>,
    /// Start a new file after this many MB (10^6 B) of messages.
    pub split_mb: Option<f64>,
    /// Record only while armed (a new file per arm period).
    pub on_arm: bool,
}

impl RecordOptions {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        RecordOptions {
            path: path.into(),
            zstd: true,
            chunk_interval: Duration::from_millis(500),
            chunk_bytes: 4 << 20,
            split_s: None,
            split_mb: None,
            on_arm: false,
        }
    }
}

/// Recorder parameters (besides `--record PATH`).
pub const RECORD_PARAMS: [&str; 7] = [
    "record",
    "record_on_arm",
    "record_split_s",
    "record_split_mb",
    "record_compression",
    "record_chunk_ms",
    "record_chunk_mb",
];

/// Recording options from `--record PATH` (wins) or `-p record:=PATH`, and `-p record_*`:
/// `record_on_arm` (false), `record_split_s`, `record_split_mb` (off), `record_compression`
/// (`zstd` | `none`, default zstd), `record_chunk_ms` (500), `record_chunk_mb` (4).
pub fn record_options(
    flag: Option<&str>,
    p: &BTreeMap<String, String>,
) -> Result<Option<RecordOptions>, String> {
    let path = flag
        .or(p.get("record").map(String::as_str))
        .map(str::trim)
        .filter(|s| !s.is_empty());
    let Some(path) = path else {
        if let Some(k) = RECORD_PARAMS[1..].iter().find(|k| p.contains_key(**k)) {
            return Err(format!(
                "parameter {k} needs --record PATH (or -p record:=PATH)"
            ));
        }
        return Ok(None);
    };
    let mut o = RecordOptions::new(path);
    let pos = |k: &str| -> Result<Option<f64>, String> {
        p.get(k)
            .map(|v| match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
                _ => Err(format!("parameter {k}: '{v}' is not a positive number")),
            })
            .transpose()
    };
    o.split_s = pos("record_split_s")?;
    o.split_mb = pos("record_split_mb")?;
    if let Some(ms) = pos("record_chunk_ms")? {
        o.chunk_interval = std::time::Duration::from_millis(ms.max(1.0) as u64);
    }
    if let Some(mb) = pos("record_chunk_mb")? {
        o.chunk_bytes = (mb * 1048576.0) as u64;
    }
    if let Some(v) = p.get("record_on_arm") {
        o.on_arm = parse_bool(v)?;
    }
    if let Some(v) = p.get("record_compression") {
        o.zstd = match v.as_str() {
            "zstd" => true,
            "none" | "" => false,
            _ => return Err(format!("parameter record_compression: '{v}' (zstd | none)")),
        };
    }
    Ok(Some(o))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_params() {
        let mut p = BTreeMap::new();
        assert!(record_options(None, &p).unwrap().is_none());
        p.insert("record_split_s".to_string(), "60".to_string());
        assert!(record_options(None, &p).is_err());
        p.insert("record".to_string(), "/tmp/a.mcap".to_string());
        let o = record_options(None, &p).unwrap().unwrap();
        assert_eq!(o.split_s, Some(60.0));
        assert!(o.zstd && !o.on_arm);
        let o = record_options(Some("/tmp/b.mcap"), &p).unwrap().unwrap();
        assert_eq!(o.path, std::path::PathBuf::from("/tmp/b.mcap"));
        p.insert("record_compression".to_string(), "lz5".to_string());
        assert!(record_options(None, &p).is_err());
    }
}
