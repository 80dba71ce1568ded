//! fcc (vendored): where the [`Writer`](crate::write::Writer) keeps its chunk indexes until
//! `finish()` writes them into the summary section.
//!
//! Upstream keeps a `Vec<ChunkIndex>` in memory for the whole recording: one entry per chunk,
//! each with a `BTreeMap` of message-index offsets (one per channel in the chunk), ≈ 750 B of
//! heap per chunk with 25 channels. A recorder that closes a chunk every 0.5 s for crash safety
//! grows by ≈ 5–6 MB an hour (heaptrack of the bridge's 30-min soak, issue 14). Here the entries
//! go, in their binary record encoding (≈ 300 B), to an anonymous temporary file (created
//! unlinked in the system's temp directory by the `tempfile` crate) and are read back once, at
//! `finish()`: the writer's memory no longer grows with the length of the recording. If no
//! temporary file can be created the entries stay in memory, as upstream does.

use std::io::{BufReader, BufWriter, Cursor, Seek, SeekFrom, Write};

use binrw::prelude::*;

use crate::{records::ChunkIndex, McapError, McapResult};

pub(crate) struct ChunkIndexStore {
    count: usize,
    spill: Option<BufWriter<std::fs::File>>,
    in_memory: Vec<ChunkIndex>,
    /// Scratch buffer for one encoded entry (reused).
    scratch: Vec<u8>,
}

impl Default for ChunkIndexStore {
    fn default() -> Self {
        Self {
            count: 0,
            spill: tempfile::tempfile().ok().map(BufWriter::new),
            in_memory: Vec::new(),
            scratch: Vec::new(),
        }
    }
}

impl ChunkIndexStore {
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.count
    }

    pub(crate) fn push(&mut self, index: ChunkIndex) -> McapResult<()> {
        match &mut self.spill {
            Some(file) => {
                self.scratch.clear();
                index.write_le(&mut Cursor::new(&mut self.scratch))?;
                file.write_all(&self.scratch)?;
            }
            None => self.in_memory.push(index),
        }
        self.count += 1;
        Ok(())
    }

    /// Every entry pushed so far, in order; the store is empty afterwards.
    pub(crate) fn take_all(&mut self) -> McapResult<Vec<ChunkIndex>> {
        let count = std::mem::take(&mut self.count);
        let Some(file) = &mut self.spill else {
            return Ok(std::mem::take(&mut self.in_memory));
        };
        file.flush()?;
        let f = file.get_mut();
        f.seek(SeekFrom::Start(0))?;
        let mut out = Vec::with_capacity(count);
        {
            let mut reader = BufReader::new(&mut *f);
            for _ in 0..count {
                out.push(ChunkIndex::read_le(&mut reader).map_err(McapError::from)?);
            }
        }
        f.set_len(0)?;
        f.seek(SeekFrom::Start(0))?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn entry(i: u64) -> ChunkIndex {
        ChunkIndex {
            message_start_time: i,
            message_end_time: i + 1,
            chunk_start_offset: 100 * i,
            chunk_length: 50,
            message_index_offsets: BTreeMap::from([(1, 100 * i + 60), (7, 100 * i + 80)]),
            message_index_length: 40,
            compression: "zstd".into(),
            compressed_size: 30,
            uncompressed_size: 90,
        }
    }

    #[test]
    fn spilled_entries_come_back_in_order_and_the_store_empties() {
        let mut s = ChunkIndexStore::default();
        assert!(s.spill.is_some(), "a temporary file was created");
        for i in 0..1000 {
            s.push(entry(i)).unwrap();
        }
        assert_eq!(s.len(), 1000);
        let all = s.take_all().unwrap();
        assert_eq!(all, (0..1000).map(entry).collect::<Vec<_>>());
        assert_eq!(s.len(), 0);
        s.push(entry(5)).unwrap();
        assert_eq!(s.take_all().unwrap(), vec![entry(5)]);
    }
}
