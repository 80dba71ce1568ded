//! Recovery of a bag the recorder could not finish (SIGKILL, power loss, a full disk): like
//! `mcap recover` or `ros2 bag reindex`, `fcc-bag-recover` reads every complete record of the
//! data section — schemas, channels, messages (loose or in complete chunks), metadata and
//! attachments — up to the first one that is cut or damaged, and writes them into a new,
//! complete MCAP (same profile, schema and channel ids, sequence numbers and times; chunks,
//! message indexes, summary with chunk indexes and Statistics, footer), which every reader
//! opens (Foxglove's `mcap`, `rosbags`, `ros2 bag`).
//!
//! What is lost is what never reached the file whole: the chunk that was open at the kill
//! (≤ [`crate::record::RecordOptions::chunk_interval`] of messages plus the writer's queue).

use mcap::records::Record;
use std::collections::BTreeMap;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// What [`recover`] found and wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Recovered {
    /// Messages written to the output.
    pub messages: u64,
    /// Messages by topic.
    pub by_topic: BTreeMap<String, u64>,
    pub schemas: u64,
    pub channels: u64,
    /// Metadata and attachment records carried over.
    pub metadata: u64,
    pub attachments: u64,
    /// Log time (ns) of the first and the last message kept.
    pub first_log_ns: Option<u64>,
    pub last_log_ns: Option<u64>,
    /// Bytes of the input file.
    pub input_bytes: u64,
    /// Bytes at the end of the input that held no complete record (the unfinished chunk).
    pub torn_bytes: u64,
    /// The input already had its data-end record (a finished bag: nothing was lost).
    pub input_complete: bool,
    /// Why reading stopped before the end of the data section, if it did.
    pub stopped: Option<String>,
}

/// The default output path: `DIR/STEM.recovered.mcap`.
pub fn default_output(input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "bag".into());
    input.with_file_name(format!("{stem}.recovered.mcap"))
}

/// End of the last record whose opcode + length framing fits in `buf` (offset after the
/// magic; records from there are read one after the other). The first record that does not fit
/// — an unfinished chunk carries the writer's placeholder length 2^64−1 — ends the scan.
pub fn framed_end(buf: &[u8]) -> u64 {
    let mut at: u64 = mcap::MAGIC.len() as u64;
    let n = buf.len() as u64;
    if n < at || buf[..mcap::MAGIC.len()] != mcap::MAGIC[..] {
        return 0;
    }
    while at + 9 <= n {
        let i = at as usize;
        let mut len = [0u8; 8];
        len.copy_from_slice(&buf[i + 1..i + 9]);
        let len = u64::from_le_bytes(len);
        match (at + 9).checked_add(len) {
            Some(end) if end <= n => at = end,
            _ => break,
        }
    }
    at
}

/// Read `input`, write the recovered bag to `output` (never the input itself).
pub fn recover(input: &Path, output: &Path) -> anyhow::Result<Recovered> {
    if let (Ok(a), Ok(b)) = (input.canonicalize(), output.canonicalize()) {
        anyhow::ensure!(
            a != b,
            "the output must not be the input ({})",
            input.display()
        );
    }
    let buf = std::fs::read(input).map_err(|e| anyhow::anyhow!("{}: {}", input.display(), e))?;
    anyhow::ensure!(
        buf.len() >= mcap::MAGIC.len() && buf[..mcap::MAGIC.len()] == mcap::MAGIC[..],
        "{}: not an MCAP file (no magic bytes)",
        input.display()
    );
    let file = std::fs::File::create(output)
        .map_err(|e| anyhow::anyhow!("{}: {}", output.display(), e))?;
    let out = BufWriter::with_capacity(1 << 20, file);
    let r = recover_bytes(&buf, out)?;
    Ok(r)
}

/// [`recover`] on bytes in memory, writing into `out`.
pub fn recover_bytes<W: Write + std::io::Seek>(buf: &[u8], out: W) -> anyhow::Result<Recovered> {
    let mut rep = Recovered {
        input_bytes: buf.len() as u64,
        ..Default::default()
    };
    let mut records = mcap::read::LinearReader::new(buf)?;
    // The header comes first; its profile is kept.
    let profile = match records.next() {
        Some(Ok(Record::Header(h))) => h.profile,
        Some(Ok(r)) => anyhow::bail!("the file starts with {:?}, not a header", r.opcode()),
        Some(Err(e)) => anyhow::bail!("header: {e}"),
        None => anyhow::bail!("empty file"),
    };
    // Compression of the output: that of the input's first chunk (zstd when there is none).
    let zstd = first_chunk_compression(buf).is_none_or(|c| c == "zstd");
    let mut w = crate::record::write_options(zstd, 4 << 20)
        .profile(profile)
        .library(concat!(
            "fcc-bag-recover ",
            env!("CARGO_PKG_VERSION"),
            " (mcap 0.26)"
        ))
        .create(out)?;
    let mut topics: BTreeMap<u16, String> = BTreeMap::new();
    'records: for r in records {
        let r = match r {
            Ok(r) => r,
            Err(e) => {
                rep.stopped = Some(e.to_string());
                break;
            }
        };
        match r {
            Record::Chunk { header, data } => {
                // A chunk is taken whole or not at all (its records are checked first), so the
                // output never holds half of one.
                let inner: Result<Vec<Record<'_>>, _> =
                    match mcap::read::ChunkReader::new(header, &data) {
                        Ok(c) => c.collect(),
                        Err(e) => Err(e),
                    };
                match inner {
                    Ok(inner) => {
                        for r in inner {
                            copy_record(&mut w, &mut topics, r, &mut rep)?;
                        }
                    }
                    Err(e) => {
                        rep.stopped = Some(format!("damaged chunk: {e}"));
                        break 'records;
                    }
                }
            }
            r => {
                if copy_record(&mut w, &mut topics, r, &mut rep)? {
                    rep.input_complete = true;
                    break;
                }
            }
        }
    }
    w.finish()?;
    let mut out = w.into_inner();
    out.flush()?;
    rep.torn_bytes = if rep.input_complete {
        0
    } else {
        buf.len() as u64 - framed_end(buf)
    };
    Ok(rep)
}

/// Copy one record of the input into the writer (schemas, channels, messages, metadata,
/// attachments; indexes and summary records are rebuilt by the writer), counting it in `rep`.
/// True at the end of the data section.
fn copy_record<W: Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    topics: &mut BTreeMap<u16, String>,
    r: Record<'_>,
    rep: &mut Recovered,
) -> anyhow::Result<bool> {
    match r {
        Record::Schema { header, data } => {
            w.add_schema_with_id(header.id, &header.name, &header.encoding, &data)?;
            rep.schemas += 1;
        }
        Record::Channel(c) => {
            w.add_channel_with_id(
                c.id,
                c.schema_id,
                &c.topic,
                &c.message_encoding,
                &c.metadata,
            )?;
            topics.insert(c.id, c.topic.clone());
            rep.channels += 1;
        }
        Record::Message { header, data } => {
            let Some(topic) = topics.get(&header.channel_id) else {
                anyhow::bail!(
                    "message {} on unknown channel {}",
                    header.sequence,
                    header.channel_id
                );
            };
            w.write_to_known_channel(&header, &data)?;
            rep.messages += 1;
            *rep.by_topic.entry(topic.clone()).or_default() += 1;
            let t = header.log_time;
            rep.first_log_ns = Some(rep.first_log_ns.map_or(t, |f| f.min(t)));
            rep.last_log_ns = Some(rep.last_log_ns.map_or(t, |l| l.max(t)));
        }
        Record::Metadata(m) => {
            w.write_metadata(&m)?;
            rep.metadata += 1;
        }
        Record::Attachment { header, data, .. } => {
            w.attach(&mcap::Attachment {
                log_time: header.log_time,
                create_time: header.create_time,
                name: header.name,
                media_type: header.media_type,
                data,
            })?;
            rep.attachments += 1;
        }
        Record::DataEnd(_) => return Ok(true),
        // Indexes and summary records are rebuilt by the writer.
        _ => {}
    }
    Ok(false)
}

/// The compression name of the first chunk in the file, if there is one whose header is whole.
fn first_chunk_compression(buf: &[u8]) -> Option<String> {
    let mut at = mcap::MAGIC.len();
    while at + 9 <= buf.len() {
        let op = buf[at];
        let mut len = [0u8; 8];
        len.copy_from_slice(&buf[at + 1..at + 9]);
        let len = u64::from_le_bytes(len);
        if op == mcap::records::op::CHUNK {
            // start, end, uncompressed size (8 each), crc (4), compression (u32 length + text).
            let s = at + 9 + 28;
            let l = u32::from_le_bytes(buf.get(s..s + 4)?.try_into().ok()?) as usize;
            return Some(String::from_utf8_lossy(buf.get(s + 4..s + 4 + l)?).into_owned());
        }
        at = at.checked_add(9)?.checked_add(usize::try_from(len).ok()?)?;
    }
    None
}

/// Seconds, for printing.
pub fn secs(ns: u64) -> f64 {
    ns as f64 / 1e9
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// A bag as a SIGKILL leaves it with the mcap crate writing chunks straight to the file
    /// (`direct`, as the recorder did before): two finished chunks, then an open one whose
    /// header still carries the placeholder length. With the recorder's options (chunks built
    /// in memory) the open chunk is not in the file at all.
    fn killed_bag_with(compression: bool, direct: bool) -> (Vec<u8>, u64, u64) {
        let mut opts = crate::record::write_options(compression, 1 << 20);
        if direct {
            opts = opts.disable_seeking(false);
        }
        let mut w = opts.create(Cursor::new(Vec::new())).unwrap();
        let sid = w
            .add_schema("std_msgs/msg/String", "ros2msg", b"string data")
            .unwrap();
        let mut md = BTreeMap::new();
        md.insert(
            "offered_qos_profiles".to_string(),
            "- history: 1\n".to_string(),
        );
        let ch = w.add_channel(sid, "/fcc/x", "cdr", &md).unwrap();
        let mut seq = 0u32;
        let mut msg = |w: &mut mcap::Writer<Cursor<Vec<u8>>>, t: u64| {
            let h = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: seq,
                log_time: t,
                publish_time: t,
            };
            seq += 1;
            w.write_to_known_channel(&h, &[0, 1, 0, 0, 2, 0, 0, 0, b'a', 0])
                .unwrap();
        };
        // Two chunks of 100 messages each, 10 ms apart, closed by flush (as the recorder does).
        for i in 0..200u64 {
            msg(&mut w, 1_000_000_000 + i * 10_000_000);
            if i == 99 || i == 199 {
                w.flush().unwrap();
            }
        }
        let last_kept = 1_000_000_000 + 199 * 10_000_000;
        // The open chunk: 30 more messages, never finished.
        for i in 200..230u64 {
            msg(&mut w, 1_000_000_000 + i * 10_000_000);
        }
        let bytes = w.into_inner().into_inner();
        (bytes, 200, last_kept)
    }

    fn killed_bag(compression: bool) -> (Vec<u8>, u64, u64) {
        killed_bag_with(compression, true)
    }

    /// The recorder's own options: a killed file ends at a record boundary (no placeholder),
    /// and recovers to the same messages.
    #[test]
    fn recorder_options_leave_no_half_chunk() {
        for zstd in [true, false] {
            let (bytes, kept, last_kept) = killed_bag_with(zstd, false);
            assert_eq!(framed_end(&bytes), bytes.len() as u64);
            assert!(!bytes
                .windows(9)
                .any(|w| w[0] == mcap::records::op::CHUNK && w[1..9] == [0xff; 8]));
            let r = recover_bytes(&bytes, Cursor::new(Vec::new())).unwrap();
            assert_eq!(
                (r.messages, r.last_log_ns, r.torn_bytes),
                (kept, Some(last_kept), 0)
            );
            assert!(!r.input_complete);
        }
    }

    #[test]
    fn a_killed_bag_is_rewritten_complete_up_to_the_open_chunk() {
        for zstd in [true, false] {
            let (bytes, kept, last_kept) = killed_bag(zstd);
            // The cut: an unfinished chunk whose length is the placeholder.
            assert!(bytes
                .windows(9)
                .any(|w| w[0] == mcap::records::op::CHUNK && w[1..9] == [0xff; 8]));
            assert!(
                mcap::Summary::read(&bytes).is_err()
                    || mcap::Summary::read(&bytes).unwrap().is_none()
            );
            let mut out = Cursor::new(Vec::new());
            let r = recover_bytes(&bytes, &mut out).unwrap();
            assert_eq!(r.messages, kept, "{r:?}");
            assert_eq!(r.by_topic.get("/fcc/x"), Some(&kept));
            assert_eq!((r.schemas, r.channels), (1, 1));
            assert_eq!(r.last_log_ns, Some(last_kept));
            assert!(!r.input_complete);
            assert!(r.torn_bytes > 0, "{r:?}");
            let out = out.into_inner();
            // A complete file: summary with chunk indexes and Statistics, every message readable.
            let s = mcap::Summary::read(&out).unwrap().expect("summary");
            assert_eq!(s.stats.as_ref().unwrap().message_count, kept);
            assert!(!s.chunk_indexes.is_empty());
            let ch = s.channels.values().next().unwrap();
            assert_eq!(ch.topic, "/fcc/x");
            assert_eq!(ch.metadata["offered_qos_profiles"], "- history: 1\n");
            let n = mcap::MessageStream::new(&out).unwrap().count();
            assert_eq!(n as u64, kept);
            let seqs: Vec<u32> = mcap::MessageStream::new(&out)
                .unwrap()
                .map(|m| m.unwrap().sequence)
                .collect();
            assert_eq!(seqs, (0..kept as u32).collect::<Vec<_>>());
            // Recovering the recovered bag changes nothing and says it was complete.
            let r2 = recover_bytes(&out, Cursor::new(Vec::new())).unwrap();
            assert!(r2.input_complete);
            assert_eq!((r2.messages, r2.torn_bytes), (kept, 0));
        }
    }

    #[test]
    fn garbage_or_a_cut_anywhere_gives_an_error_or_a_prefix_never_a_panic() {
        let (bytes, kept, _) = killed_bag(true);
        assert!(recover_bytes(b"not an mcap", Cursor::new(Vec::new())).is_err());
        assert!(recover_bytes(&[], Cursor::new(Vec::new())).is_err());
        // Cut at every length (step 7): whatever is read is a prefix of the messages.
        let mut last = 0;
        for cut in (0..bytes.len()).step_by(7) {
            if let Ok(r) = recover_bytes(&bytes[..cut], Cursor::new(Vec::new())) {
                assert!(r.messages <= kept);
                assert!(r.messages >= last, "monotone in the cut");
                last = r.messages;
            }
        }
        assert_eq!(last, kept);
        // A damaged byte inside the first chunk's compressed data: stop there, keep nothing
        // after it, report why.
        let mut at = mcap::MAGIC.len();
        while bytes[at] != mcap::records::op::CHUNK {
            at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        }
        for k in [60, 120, 400] {
            let mut bad = bytes.clone();
            bad[at + k] ^= 0x5a;
            if let Ok(r) = recover_bytes(&bad, Cursor::new(Vec::new())) {
                assert!(r.messages <= kept, "{r:?}");
            }
        }
    }

    #[test]
    fn framing_scan_stops_at_the_placeholder() {
        let (bytes, _, _) = killed_bag(false);
        let end = framed_end(&bytes) as usize;
        assert!(end < bytes.len());
        assert_eq!(bytes[end], mcap::records::op::CHUNK);
        assert_eq!(bytes[end + 1..end + 9], [0xff; 8]);
        assert_eq!(framed_end(b"junk"), 0);
        assert_eq!(
            default_output(Path::new("/x/k.mcap")),
            PathBuf::from("/x/k.recovered.mcap")
        );
    }
}
