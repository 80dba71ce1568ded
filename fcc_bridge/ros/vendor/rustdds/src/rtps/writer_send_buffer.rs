use std::{
  cmp::max,
  collections::{BTreeMap, VecDeque},
  sync::{Arc, Condvar, Mutex},
  time::{Duration as StdDuration, Instant},
};
use core::task::Waker;

#[allow(unused_imports)]
use log::{debug, error, trace, warn};

use crate::{
  dds::{ddsdata::DDSData, with_key::datawriter::WriteOptions},
  structure::{cache_change::CacheChange, guid::GUID, sequence_number::SequenceNumber},
};

/// Result of an admission attempt into the [`WriterSendBuffer`].
pub(crate) enum Admission {
  /// The sample was admitted and given this sequence number. It now lives in
  /// the send buffer and is ready for the Writer (event loop) to transmit.
  Admitted(SequenceNumber),
  /// The reliable send window is full and no room became available within the
  /// allotted blocking time. The sample was *not* stored.
  WouldBlock,
}

// The actual shared state. Guarded by a single Mutex; the Condvar is signalled
// whenever the reliable acknowledgement frontier advances or the window grows,
// i.e. whenever a previously-blocked producer (or a `wait_for_acknowledgments`
// waiter) might be able to make progress.
struct Inner {
  // --- the send buffer proper (replaces the old HistoryBuffer) ---
  // Keyed by SequenceNumber, which is allocated here under the lock and is thus
  // strictly monotonic and unique. This is the single source of truth for the
  // Writer's outgoing samples (send, repair, fragmentation, eviction).
  // fcc (vendored): for a user writer a ring of consecutive sequence numbers, not a BTreeMap
  // (see `Changes`).
  changes: Changes,
  first_seq: SequenceNumber, // oldest still retained (default 1)
  last_seq: SequenceNumber,  // latest allocated (default 0 == nothing yet)

  // --- flow control ---
  // Maximum number of unacknowledged samples a reliable writer may have
  // outstanding before `write` must block/fail.
  window_limit: usize,
  // The acknowledgement frontier: the smallest `all_acked_before` over all
  // matched *reliable* readers. Only meaningful when `reliable_readers_present`.
  // Maintained by the Writer (event loop) via `set_acked_frontier`.
  acked_before: SequenceNumber,
  reliable_readers_present: bool,

  // nonblocking-transmit: the unsent backlog limit. The Writer advances
  // `sent_frontier` as it actually transmits samples; when the network socket
  // congests, `sent_frontier` stalls, the backlog `(sent_frontier, last_seq]`
  // fills, and admission blocks -- back-pressure reaching the application.
  // Applies to reliable *and* best-effort writers; built-in/discovery are
  // exempt so discovery never stalls.
  // (see src/rtps/nonblocking_transmit_design.md)
  backlog_limit: usize,
  // Highest sequence number the Writer has actually put on the wire.
  sent_frontier: SequenceNumber,

  // Hard upper bound on the number of retained samples for *non-blocking*
  // (best-effort, DDS-default) writes. Because such writes are never throttled
  // at admission (see `has_room`), and eviction otherwise only happens on the
  // periodic (6 s) cache-cleaning timer, the buffer would grow without bound
  // when the application produces faster than the socket drains. We therefore
  // apply KeepLast-style "newest wins" eviction directly on insert: once the
  // buffer exceeds `max_retain`, the oldest samples are dropped. Derived from
  // the writer's History depth / ResourceLimits (same value as `window_limit`).
  // Does NOT apply to reliable / opted-in writers, which are bounded by the
  // send window / unsent-backlog and must retain samples for repair.
  max_retain: usize,

  // Wakers of async producers / ack-waiters parked because the window was full
  // or acknowledgements were still pending. Drained (woken) on any advance.
  wakers: Vec<Waker>,

  // fcc (vendored): threads waiting on `Shared::progress` (counted under the lock). std's
  // futex Condvar makes a FUTEX_WAKE system call on every notify, waiter or not, and
  // `set_sent_frontier` notified after every sample sent.
  waiters: usize,
}

struct Shared {
  inner: Mutex<Inner>,
  // Signalled together with `wakers` whenever progress may be possible.
  progress: Condvar,
  // Fixed for the lifetime of the writer.
  writer_guid: GUID,
  reliable_writer: bool,
  is_builtin: bool,
  // True for VOLATILE durability (the DDS default). When true, a reliable writer
  // with no matched reliable reader trims KeepLast on insert (there is no
  // late-joiner to serve, so retaining unacked samples is pointless). When false
  // (TRANSIENT_LOCAL / TRANSIENT / PERSISTENT) the writer must retain samples for
  // late-joining readers, so pre-match trimming is disabled.
  volatile: bool,
  topic_name: String,
}

/// A shared, flow-controlled buffer of samples between a `DataWriter`
/// (producer, application threads) and its RTPS `Writer` (consumer, event
/// loop).
///
/// The producer side allocates a sequence number and inserts a sample only when
/// the reliable send window has room (synchronous admission, no round-trip).
/// The consumer side transmits unsent samples, advances the acknowledgement
/// frontier as ACKNACKs arrive, and evicts acknowledged samples. Both sides
/// hold a cloned handle to the same `Arc`.
#[derive(Clone)]
pub(crate) struct WriterSendBuffer {
  shared: Arc<Shared>,
}

impl WriterSendBuffer {
  #[allow(clippy::too_many_arguments)]
  pub fn new(
    writer_guid: GUID,
    topic_name: String,
    reliable_writer: bool,
    is_builtin: bool,
    volatile: bool,
    window_limit: usize,
    backlog_limit: usize,
    max_retain: usize,
  ) -> Self {
    Self {
      shared: Arc::new(Shared {
        inner: Mutex::new(Inner {
          changes: Changes::new(is_builtin),
          first_seq: SequenceNumber::new(1),
          last_seq: SequenceNumber::new(0),
          window_limit: window_limit.max(1),
          acked_before: SequenceNumber::new(1),
          reliable_readers_present: false,
          backlog_limit: backlog_limit.max(1),
          sent_frontier: SequenceNumber::new(0),
          max_retain: max_retain.max(1),
          wakers: Vec::new(),
          waiters: 0,
        }),
        progress: Condvar::new(),
        writer_guid,
        reliable_writer,
        is_builtin,
        volatile,
        topic_name,
      }),
    }
  }

  // --- predicates (must be called while holding the lock) ---

  // Is there room to admit one more sample right now?
  //
  // `may_block` is `true` for reliable writers and for best-effort writes that
  // opted in via `WriteOptions::best_effort_may_block`. When `false` (a
  // best-effort write that must not block, the DDS default) admission is never
  // throttled: congested samples are dropped later at the socket instead.
  fn has_room(shared: &Shared, inner: &Inner, may_block: bool) -> bool {
    if shared.is_builtin {
      // Built-in (discovery) writers must never stall.
      return true;
    }

    if !may_block {
      // Best-effort write that must not block (DDS v1.4 2.2.2.4.2.11 default).
      // Never throttle admission.
      return true;
    }

    // nonblocking-transmit: unsent-backlog limit. Applies to reliable writers
    // and to best-effort writers that opted in -- when the socket cannot drain,
    // the application is back-pressured instead of dropping. Samples in
    // (sent_frontier, last_seq].
    let unsent = i64::from(inner.last_seq) - i64::from(inner.sent_frontier);
    if unsent >= inner.backlog_limit as i64 {
      return false;
    }

    if !shared.reliable_writer || !inner.reliable_readers_present {
      // Best-effort and "no reliable reader yet" writers have no acknowledgement
      // window to wait on; the backlog limit above is their only throttle.
      return true;
    }
    // Number of unacknowledged samples in [acked_before, last_seq].
    let unacked = i64::from(inner.last_seq) - i64::from(inner.acked_before) + 1;
    unacked < inner.window_limit as i64
  }

  // Wake every parked producer / ack-waiter. Called after any state change that
  // could let someone make progress.
  fn wake_all(inner: &mut Inner, progress: &Condvar) {
    for w in inner.wakers.drain(..) {
      w.wake();
    }
    // fcc (vendored): no system call when nobody waits (see `Inner::waiters`).
    if inner.waiters > 0 {
      progress.notify_all();
    }
  }

  // --- producer side ---

  /// Synchronous admission. Blocks the calling thread until there is room in
  /// the reliable send window, or `timeout` elapses. On success the sample is
  /// stored and its sequence number returned. Built-in / best-effort writers
  /// always admit immediately.
  pub fn admit_blocking(
    &self,
    write_options: WriteOptions,
    data: DDSData,
    timeout: Option<StdDuration>,
  ) -> Admission {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();

    // Reliable writers always back-pressure; best-effort only if this write
    // opted in via `best_effort_may_block`.
    let may_block = shared.reliable_writer || write_options.best_effort_may_block();

    let deadline = timeout.map(|t| Instant::now() + t);
    loop {
      if Self::has_room(shared, &inner, may_block) {
        let seq = Self::insert_locked(shared, &mut inner, write_options, data, may_block);
        return Admission::Admitted(seq);
      }
      // Window full: wait for an acknowledgement to free up space.
      // fcc (vendored): the samples held in the window may not have been sent yet when the
      // caller is inside `polling::defer_wakes`: wake the event loop before waiting.
      crate::polling::flush_deferred_wakes();
      match deadline {
        None => {
          inner.waiters += 1; // fcc (vendored)
          inner = shared.progress.wait(inner).unwrap();
          inner.waiters -= 1;
        }
        Some(deadline) => {
          let now = Instant::now();
          if now >= deadline {
            return Admission::WouldBlock;
          }
          inner.waiters += 1; // fcc (vendored)
          let (guard, _timeout_result) =
            shared.progress.wait_timeout(inner, deadline - now).unwrap();
          inner = guard;
          inner.waiters -= 1;
        }
      }
    }
  }

  /// Non-blocking admission for async writers. On success returns the allocated
  /// sequence number. On a full window returns the (write_options, data) back
  /// so the caller can retry later, and registers `waker` to be woken when
  /// room becomes available.
  pub fn try_admit(
    &self,
    write_options: WriteOptions,
    data: DDSData,
    waker: &Waker,
  ) -> Result<SequenceNumber, (WriteOptions, DDSData)> {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();
    let may_block = shared.reliable_writer || write_options.best_effort_may_block();
    if Self::has_room(shared, &inner, may_block) {
      Ok(Self::insert_locked(
        shared,
        &mut inner,
        write_options,
        data,
        may_block,
      ))
    } else {
      register_waker(&mut inner.wakers, waker);
      Err((write_options, data))
    }
  }

  fn insert_locked(
    shared: &Shared,
    inner: &mut Inner,
    write_options: WriteOptions,
    data: DDSData,
    may_block: bool,
  ) -> SequenceNumber {
    let seq = inner.last_seq.plus_1();
    let cc = CacheChange::new(shared.writer_guid, seq, write_options, data);
    inner.changes.push(seq, cc);
    inner.last_seq = seq;

    // KeepLast "newest wins" bound. Applied on insert for:
    //  - non-blocking best-effort writes: never throttled at admission (`has_room`
    //    returns true), and the only other eviction path is the periodic
    //    cache-cleaning timer, which starves under a sustained flood -- so without
    //    this the buffer grows without bound (confirmed multi-GB leak);
    //  - reliable writers with NO matched reliable reader yet: there is nobody to
    //    repair to, so retaining unacknowledged samples is pointless. A reliable
    //    writer that produces flat-out before discovery completes (discovery is
    //    CPU-starved under load and can lag ~1 s) would otherwise race thousands of
    //    samples ahead, and when the reader finally matches it faces a huge
    //    unacknowledged backlog that must be recovered via repair at the slow (100
    //    ms) heartbeat cadence -- collapsing reliable throughput. Trimming to
    //    KeepLast here keeps only the recent samples (correct for volatile
    //    durability); once a reliable reader matches, `reliable_readers_present`
    //    flips true and we retain everything again for repair.
    // Built-in (discovery) writers are always exempt to never lose discovery data.
    let trim_keep_last = !shared.is_builtin
      && (!may_block
        || (shared.reliable_writer && shared.volatile && !inner.reliable_readers_present));
    if trim_keep_last {
      while inner.changes.len() > inner.max_retain {
        // The first entry is the oldest SN.
        let oldest = match inner.changes.first_key() {
          Some(sn) => sn,
          None => break,
        };
        inner.changes.remove(oldest);
        inner.first_seq = oldest.plus_1();
      }
    }
    seq
  }

  // --- consumer side (Writer / event loop) ---

  /// Update the reliable acknowledgement frontier. `acked_before` is the
  /// minimum `all_acked_before` over all matched reliable readers, and
  /// `present` tells whether any reliable reader is currently matched. Wakes
  /// blocked producers / ack-waiters when the frontier advances or a reader
  /// goes away.
  ///
  /// A reader that has not sent an ACKNACK yet reports `all_acked_before == 0`.
  /// Sequence numbers start at 1, so the frontier is never below 1: anything
  /// lower would count a sample that does not exist against the send window.
  pub fn set_acked_frontier(&self, acked_before: Option<SequenceNumber>) {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();
    let advanced = match acked_before {
      Some(sn) => {
        let sn = max(sn, SequenceNumber::new(1));
        let adv = sn > inner.acked_before || !inner.reliable_readers_present;
        inner.acked_before = sn;
        inner.reliable_readers_present = true;
        adv
      }
      None => {
        // No reliable readers (any more). Everything counts as acknowledged.
        let adv = inner.reliable_readers_present;
        inner.reliable_readers_present = false;
        adv
      }
    };
    if advanced {
      Self::wake_all(&mut inner, &shared.progress);
    }
  }

  /// nonblocking-transmit: advance the "actually transmitted" frontier. Called
  /// by the Writer as it puts samples on the wire. Wakes producers parked on a
  /// full unsent backlog when the frontier advances.
  pub fn set_sent_frontier(&self, sent_frontier: SequenceNumber) {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();
    if sent_frontier > inner.sent_frontier {
      inner.sent_frontier = sent_frontier;
      Self::wake_all(&mut inner, &shared.progress);
    }
  }

  /// fcc (vendored): whether a HEARTBEAT piggybacked on DATA should ask the readers for an
  /// ACKNACK (final flag clear): always for a built-in writer or one without a reliable reader,
  /// else once the matched reliable readers have left a third of the send window (this sample
  /// included) unacknowledged. Asking on every sample made the reader answer every sample: one
  /// datagram and one wake of the event loop each, the bridge's largest per-sample cost. The
  /// readers still answer a final HEARTBEAT when they miss a sample (RTPS 8.4.15.6 / 8.3.7.5),
  /// and from a third of the window on every sample asks again until the ACKNACK comes. The
  /// cost: when a reader stops answering, up to a third of the window may already be
  /// unacknowledged, so a full window comes that many samples sooner (depth 10: after 7 more
  /// samples at worst instead of 9).
  pub fn ack_wanted(&self) -> bool {
    let shared = &*self.shared;
    let inner = shared.inner.lock().unwrap();
    if shared.is_builtin || !shared.reliable_writer || !inner.reliable_readers_present {
      return true;
    }
    let unacked = i64::from(inner.last_seq) - i64::from(inner.acked_before) + 1;
    unacked >= (inner.window_limit / 3).max(1) as i64
  }

  /// The sequence number of the latest allocated sample (0 if none yet).
  pub fn last_change_sequence_number(&self) -> SequenceNumber {
    self.shared.inner.lock().unwrap().last_seq
  }

  /// Number of samples currently retained in the buffer. Test-only.
  #[cfg(test)]
  pub fn retained_len(&self) -> usize {
    self.shared.inner.lock().unwrap().changes.len()
  }

  /// The lowest sequence number still retained (or the next-to-be-written if
  /// the buffer is empty).
  pub fn first_change_sequence_number(&self) -> SequenceNumber {
    self.shared.inner.lock().unwrap().first_seq
  }

  /// Fetch a clone of the sample with the given sequence number, if retained.
  /// Returns an owned `CacheChange` (a cheap `Bytes`-backed clone) so the
  /// caller can serialize and transmit without holding the lock.
  pub fn get_by_sn(&self, sn: SequenceNumber) -> Option<CacheChange> {
    self.shared.inner.lock().unwrap().changes.get(sn).cloned()
  }

  /// Evict all samples with sequence number strictly less than `remove_before`.
  pub fn remove_changes_before(&self, remove_before: SequenceNumber) {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();
    let count_before = inner.changes.len();
    inner.changes.remove_before(remove_before);
    if remove_before > inner.first_seq {
      inner.first_seq = remove_before;
    }
    let count_after = inner.changes.len();
    if count_before != count_after {
      debug!(
        "WriterSendBuffer: removed {} change(s) before {:?} topic={}",
        count_before - count_after,
        remove_before,
        shared.topic_name
      );
    }
  }

  /// fcc (vendored): drop one sample that a later sample of the same instance
  /// supersedes (Discovery's SEDP re-announcement of a local endpoint). Its
  /// SequenceNumber becomes a hole: a reader that still asks for it gets a GAP
  /// (the repair path), and it is not sent fresh. When it was the oldest
  /// retained sample, the oldest retained one moves up, as after eviction.
  pub fn remove_superseded(&self, sn: SequenceNumber) {
    let mut inner = self.shared.inner.lock().unwrap();
    if inner.changes.remove(sn).is_some() && sn == inner.first_seq {
      let next = inner.last_seq.plus_1();
      inner.first_seq = inner.changes.first_key().unwrap_or(next);
    }
  }

  // --- wait_for_acknowledgments support ---

  /// Has every matched reliable reader acknowledged everything up to and
  /// including `target`? Also true when there are no reliable readers.
  pub fn is_acked_through(&self, target: SequenceNumber) -> bool {
    let inner = self.shared.inner.lock().unwrap();
    !inner.reliable_readers_present || inner.acked_before > target
  }

  /// Synchronously wait until everything up to `target` is acknowledged, or
  /// `max_wait` elapses. Returns `true` if acknowledged.
  pub fn wait_for_acked_through(&self, target: SequenceNumber, max_wait: StdDuration) -> bool {
    let shared = &*self.shared;
    let mut inner = shared.inner.lock().unwrap();
    let deadline = Instant::now() + max_wait;
    loop {
      if !inner.reliable_readers_present || inner.acked_before > target {
        return true;
      }
      let now = Instant::now();
      if now >= deadline {
        return false;
      }
      // fcc (vendored): wake the event loop for samples written inside `defer_wakes`.
      crate::polling::flush_deferred_wakes();
      inner.waiters += 1; // fcc (vendored): see `Inner::waiters`
      let (guard, _to) = shared.progress.wait_timeout(inner, deadline - now).unwrap();
      inner = guard;
      inner.waiters -= 1;
    }
  }

  /// Register `waker` to be notified when the acknowledgement frontier advances
  /// (used by the async `wait_for_acknowledgments` future).
  pub fn register_ack_waker(&self, waker: &Waker) {
    let mut inner = self.shared.inner.lock().unwrap();
    register_waker(&mut inner.wakers, waker);
  }
}

/// fcc (vendored): the retained samples by SequenceNumber. A user writer's buffer allocates
/// the numbers itself, consecutively, and drops samples only from the oldest end (eviction,
/// acknowledgement), so a ring indexed by `sn - base` (`Ring`) does what the BTreeMap did
/// (insert, look-up, remove, drop all below) without a tree search, node allocation or
/// rebalancing per sample. Built-in writers keep the BTreeMap: the SEDP writer removes
/// superseded samples from the middle of a long-lived KeepAll history, which in a ring would
/// leave holes that are only freed when the oldest sample goes.
enum Changes {
  Ring(Ring),
  Tree(BTreeMap<SequenceNumber, CacheChange>),
}

impl Changes {
  fn new(is_builtin: bool) -> Self {
    if is_builtin {
      Changes::Tree(BTreeMap::new())
    } else {
      Changes::Ring(Ring::default())
    }
  }

  fn push(&mut self, sn: SequenceNumber, cc: CacheChange) {
    match self {
      Changes::Ring(r) => r.push(sn, cc),
      Changes::Tree(t) => {
        t.insert(sn, cc);
      }
    }
  }

  fn get(&self, sn: SequenceNumber) -> Option<&CacheChange> {
    match self {
      Changes::Ring(r) => r.get(sn),
      Changes::Tree(t) => t.get(&sn),
    }
  }

  fn remove(&mut self, sn: SequenceNumber) -> Option<CacheChange> {
    match self {
      Changes::Ring(r) => r.remove(sn),
      Changes::Tree(t) => t.remove(&sn),
    }
  }

  /// Drop every sample below `before`.
  fn remove_before(&mut self, before: SequenceNumber) {
    match self {
      Changes::Ring(r) => r.remove_before(before),
      Changes::Tree(t) => *t = t.split_off(&before),
    }
  }

  fn first_key(&self) -> Option<SequenceNumber> {
    match self {
      Changes::Ring(r) => r.first_key(),
      Changes::Tree(t) => t.keys().next().copied(),
    }
  }

  fn len(&self) -> usize {
    match self {
      Changes::Ring(r) => r.len,
      Changes::Tree(t) => t.len(),
    }
  }
}

/// fcc (vendored): see [`Changes`]. Numbers skipped (none today) or removed in the middle are
/// holes (`None`).
#[derive(Default)]
struct Ring {
  // SequenceNumber of `slots[0]`; when `len > 0`, `slots[0]` is `Some` (the oldest retained).
  base: i64,
  slots: VecDeque<Option<CacheChange>>,
  len: usize,
}

impl Ring {
  fn index(&self, sn: SequenceNumber) -> Option<usize> {
    let d = i64::from(sn) - self.base;
    (d >= 0 && (d as u64) < self.slots.len() as u64).then_some(d as usize)
  }

  /// Store `cc` as `sn`, newer than every retained sample (numbers in between, if any, holes).
  fn push(&mut self, sn: SequenceNumber, cc: CacheChange) {
    let sn = i64::from(sn);
    if self.len == 0 {
      self.slots.clear();
      self.base = sn;
    }
    let next = self.base + self.slots.len() as i64;
    debug_assert!(sn >= next, "WriterSendBuffer: sequence number out of order");
    for _ in next..sn {
      self.slots.push_back(None);
    }
    self.slots.push_back(Some(cc));
    self.len += 1;
  }

  fn get(&self, sn: SequenceNumber) -> Option<&CacheChange> {
    self.index(sn).and_then(|i| self.slots[i].as_ref())
  }

  fn remove(&mut self, sn: SequenceNumber) -> Option<CacheChange> {
    let i = self.index(sn)?;
    let cc = self.slots[i].take()?;
    self.len -= 1;
    self.trim_front();
    Some(cc)
  }

  /// Drop every sample below `before`.
  fn remove_before(&mut self, before: SequenceNumber) {
    let before = i64::from(before);
    while self.base < before {
      match self.slots.pop_front() {
        Some(slot) => {
          if slot.is_some() {
            self.len -= 1;
          }
          self.base += 1;
        }
        None => break,
      }
    }
    self.trim_front();
  }

  fn first_key(&self) -> Option<SequenceNumber> {
    (self.len > 0).then(|| SequenceNumber::new(self.base))
  }

  // Keep `slots[0]` a sample (holes at the front dropped).
  fn trim_front(&mut self) {
    if self.len == 0 {
      self.slots.clear();
      return;
    }
    while let Some(None) = self.slots.front() {
      self.slots.pop_front();
      self.base += 1;
    }
  }
}

// Avoid storing duplicate wakers for the same task.
fn register_waker(wakers: &mut Vec<Waker>, waker: &Waker) {
  if !wakers.iter().any(|w| w.will_wake(waker)) {
    wakers.push(waker.clone());
  }
}

#[cfg(test)]
mod tests {
  use std::time::Duration as StdDuration;

  use super::*;
  use crate::{
    dds::{ddsdata::DDSData, with_key::datawriter::WriteOptionsBuilder},
    messages::submessages::elements::serialized_payload::SerializedPayload,
    structure::guid::GUID,
    RepresentationIdentifier,
  };

  fn sample() -> DDSData {
    DDSData::new(SerializedPayload::new(
      RepresentationIdentifier::CDR_LE,
      vec![0u8; 8],
    ))
  }

  // fcc (vendored): the ring (user writers) and the BTreeMap (built-in writers) keep the same
  // samples through pushes, look-ups, removal in the middle and at the oldest end, and
  // dropping everything below a number.
  #[test]
  fn ring_and_tree_agree() {
    let guid = GUID::dummy_test_guid(crate::structure::guid::EntityKind::WRITER_NO_KEY_USER_DEFINED);
    let cc = |n: i64| {
      CacheChange::new(
        guid,
        SequenceNumber::new(n),
        WriteOptions::default(),
        sample(),
      )
    };
    let mut ring = Changes::new(false);
    let mut tree = Changes::new(true);
    assert!(matches!(ring, Changes::Ring(_)) && matches!(tree, Changes::Tree(_)));
    let check = |ring: &Changes, tree: &Changes| {
      assert_eq!(ring.len(), tree.len());
      assert_eq!(ring.first_key(), tree.first_key());
      for n in 0..40 {
        let sn = SequenceNumber::new(n);
        assert_eq!(
          ring.get(sn).map(|c| c.sequence_number),
          tree.get(sn).map(|c| c.sequence_number),
          "sn {n}"
        );
      }
    };
    for n in 1..=10 {
      ring.push(SequenceNumber::new(n), cc(n));
      tree.push(SequenceNumber::new(n), cc(n));
    }
    check(&ring, &tree);
    for n in [5, 1, 2, 10, 42, 0] {
      let sn = SequenceNumber::new(n);
      assert_eq!(
        ring.remove(sn).map(|c| c.sequence_number),
        tree.remove(sn).map(|c| c.sequence_number)
      );
      check(&ring, &tree);
    }
    // After the newest was removed, the next number leaves a hole (10).
    for n in 11..=14 {
      ring.push(SequenceNumber::new(n), cc(n));
      tree.push(SequenceNumber::new(n), cc(n));
    }
    check(&ring, &tree);
    for before in [4, 6, 6, 12, 30] {
      ring.remove_before(SequenceNumber::new(before));
      tree.remove_before(SequenceNumber::new(before));
      check(&ring, &tree);
    }
    assert_eq!(ring.len(), 0);
    // Empty: the next push starts the ring anew at its number.
    ring.push(SequenceNumber::new(31), cc(31));
    tree.push(SequenceNumber::new(31), cc(31));
    check(&ring, &tree);
  }

  // fcc (vendored): `Inner::waiters` gates `notify_all`. Threads parked on `progress` (a
  // producer on a full backlog, without and with a deadline, and an ack-waiter) are counted
  // while they wait and woken by the event loop's frontier updates; the count returns to 0,
  // so a later notify is skipped only when nobody waits.
  #[test]
  fn parked_threads_counted_and_woken() {
    use std::{sync::mpsc, thread};
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ true,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1000,
      /* backlog_limit */ 1,
      /* max_retain */ 1000,
    );
    let waiters = |b: &WriterSendBuffer| b.shared.inner.lock().unwrap().waiters;
    let wait_for_waiters = |b: &WriterSendBuffer, n: usize| {
      let t0 = Instant::now();
      while waiters(b) != n {
        assert!(t0.elapsed() < StdDuration::from_secs(10), "waiters {} != {n}", waiters(b));
        thread::sleep(StdDuration::from_millis(1));
      }
    };
    for round in 0..50 {
      // One unsent sample fills the backlog (limit 1).
      assert!(admit_now(&buf, WriteOptions::default()), "round {round}");
      let (tx, rx) = mpsc::channel();
      let (b1, t1) = (buf.clone(), tx.clone());
      let p1 = thread::spawn(move || {
        let r = b1.admit_blocking(WriteOptions::default(), sample(), None);
        t1.send(matches!(r, Admission::Admitted(_))).unwrap();
      });
      let (b2, t2) = (buf.clone(), tx.clone());
      let p2 = thread::spawn(move || {
        let r = b2.admit_blocking(
          WriteOptions::default(),
          sample(),
          Some(StdDuration::from_secs(60)),
        );
        t2.send(matches!(r, Admission::Admitted(_))).unwrap();
      });
      wait_for_waiters(&buf, 2);
      // The event loop sends the sample: both producers may go on (one after the other: the
      // first one admitted fills the backlog again, so the sample is sent once more).
      let last = buf.last_change_sequence_number();
      buf.set_sent_frontier(last);
      let first = rx.recv_timeout(StdDuration::from_secs(10)).expect("a parked producer was not woken");
      assert!(first);
      buf.set_sent_frontier(buf.last_change_sequence_number());
      let second = rx.recv_timeout(StdDuration::from_secs(10)).expect("a parked producer was not woken");
      assert!(second);
      p1.join().unwrap();
      p2.join().unwrap();
      assert_eq!(waiters(&buf), 0);
      buf.set_sent_frontier(buf.last_change_sequence_number());
    }
    // An ack-waiter, woken by the acknowledgement frontier.
    buf.set_acked_frontier(Some(SequenceNumber::new(1)));
    let target = buf.last_change_sequence_number();
    let b3 = buf.clone();
    let (tx, rx) = mpsc::channel();
    let w = thread::spawn(move || {
      tx.send(b3.wait_for_acked_through(target, StdDuration::from_secs(60))).unwrap();
    });
    wait_for_waiters(&buf, 1);
    buf.set_acked_frontier(Some(target.plus_1()));
    assert!(rx.recv_timeout(StdDuration::from_secs(10)).expect("the ack-waiter was not woken"));
    w.join().unwrap();
    // A wait that times out leaves the count at 0 too.
    assert!(!buf.wait_for_acked_through(target.plus_1(), StdDuration::from_millis(5)));
    assert_eq!(waiters(&buf), 0);
  }

  fn admit_now(buf: &WriterSendBuffer, opts: WriteOptions) -> bool {
    matches!(
      buf.admit_blocking(opts, sample(), Some(StdDuration::ZERO)),
      Admission::Admitted(_)
    )
  }

  fn may_block_opts() -> WriteOptions {
    WriteOptionsBuilder::new()
      .best_effort_may_block(true)
      .build()
  }

  // A matched reliable reader that has not sent an ACKNACK yet reports
  // `all_acked_before == 0`. Sequence numbers start at 1, so that frontier
  // leaves nothing unacknowledged on a fresh writer: the window must still
  // admit `window_limit` samples.
  #[test]
  fn unacknowledged_reader_frontier_leaves_full_window() {
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ true,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1,
      /* backlog_limit */ 1000,
      /* max_retain */ 1,
    );
    buf.set_acked_frontier(Some(SequenceNumber::zero()));

    assert!(admit_now(&buf, WriteOptions::default())); // seq 1
    assert!(!admit_now(&buf, WriteOptions::default())); // window full

    // The reader's first ACKNACK acknowledges seq 1.
    buf.set_acked_frontier(Some(SequenceNumber::new(2)));
    assert!(admit_now(&buf, WriteOptions::default())); // seq 2
  }

  // nonblocking-transmit: a best-effort writer that opted in via
  // `best_effort_may_block` is throttled by the unsent-backlog limit once the
  // socket stops draining, and released when the Writer advances the sent
  // frontier.
  #[test]
  fn backlog_limit_backpressures_best_effort_when_may_block() {
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ false,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1000,
      /* backlog_limit */ 2,
      /* max_retain */ 1000,
    );

    // Nothing sent yet: backlog fills after two admissions.
    assert!(admit_now(&buf, may_block_opts())); // seq 1
    assert!(admit_now(&buf, may_block_opts())); // seq 2
    assert!(!admit_now(&buf, may_block_opts())); // backlog full (2 unsent, limit 2)

    // The Writer transmits seq 1; backlog drops to 1, room opens for one more.
    buf.set_sent_frontier(SequenceNumber::new(1));
    assert!(admit_now(&buf, may_block_opts())); // seq 3
    assert!(!admit_now(&buf, may_block_opts())); // full again (2 unsent: seq
                                                 // 2,3)
  }

  // By default (`best_effort_may_block == false`, DDS v1.4 2.2.2.4.2.11) a
  // best-effort write is never throttled at admission, even when the backlog is
  // already full -- congested samples are dropped later at the socket instead.
  #[test]
  fn backlog_limit_ignored_for_best_effort_by_default() {
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ false,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1000,
      /* backlog_limit */ 1,
      /* max_retain */ 1000,
    );
    // Default WriteOptions => best_effort_may_block == false => never blocks.
    assert!(admit_now(&buf, WriteOptions::default()));
    assert!(admit_now(&buf, WriteOptions::default()));
    assert!(admit_now(&buf, WriteOptions::default())); // still admitted despite
                                                       // full backlog
  }

  // Built-in (discovery) writers must never be throttled by the backlog.
  #[test]
  fn backlog_limit_exempts_builtin() {
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      false,
      /* is_builtin */ true,
      /* volatile */ true,
      1000,
      /* backlog_limit */ 1,
      /* max_retain */ 1000,
    );
    assert!(admit_now(&buf, may_block_opts()));
    assert!(admit_now(&buf, may_block_opts()));
    assert!(admit_now(&buf, may_block_opts())); // still admitted despite tiny
                                                // backlog limit
  }

  // A best-effort (non-blocking, DDS-default) writer is never throttled at
  // admission, but the retained buffer must stay bounded by `max_retain`
  // (KeepLast "newest wins"): the leak fix. Every write is admitted, yet the
  // buffer never holds more than `max_retain` samples, and it retains the
  // newest ones (oldest are evicted on insert).
  #[test]
  fn best_effort_default_bounded_by_max_retain() {
    let max_retain = 4;
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ false,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1000,
      /* backlog_limit */ 1000,
      max_retain,
    );

    for _ in 0..100 {
      // Default WriteOptions => best-effort, non-blocking => always admitted.
      assert!(admit_now(&buf, WriteOptions::default()));
      // Invariant after every insert: never exceeds the retain bound.
      assert!(buf.retained_len() <= max_retain);
    }

    // Exactly `max_retain` retained, and they are the newest sequence numbers.
    assert_eq!(buf.retained_len(), max_retain);
    let last = buf.last_change_sequence_number();
    assert_eq!(last, SequenceNumber::new(100));
    let first = buf.first_change_sequence_number();
    assert_eq!(first, SequenceNumber::new(100 - max_retain as i64 + 1));
    // Newest is retained, an evicted older one is gone.
    assert!(buf.get_by_sn(last).is_some());
    assert!(buf.get_by_sn(SequenceNumber::new(1)).is_none());
  }

  // A durable (non-VOLATILE) reliable writer must NOT drop on insert even before
  // a reader matches: it retains samples for late-joining readers. The
  // `max_retain` bound does not apply to it.
  #[test]
  fn durable_reliable_writer_not_trimmed_before_match() {
    let max_retain = 2;
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ true,
      /* is_builtin */ false,
      /* volatile */ false, // TRANSIENT_LOCAL etc: keep for late joiners
      /* window_limit */ 1000,
      /* backlog_limit */ 1000,
      max_retain,
    );
    // No reliable readers matched yet => admission not window-throttled.
    for _ in 0..10 {
      assert!(admit_now(&buf, WriteOptions::default()));
    }
    // Durable path keeps everything for potential late-joiner delivery / repair
    // despite tiny max_retain.
    assert_eq!(buf.retained_len(), 10);
  }

  // A VOLATILE reliable writer with no matched reliable reader trims KeepLast on
  // insert: there is no late joiner to serve, so retaining unacknowledged samples
  // is pointless and would create a huge post-match repair backlog (the reliable
  // flat-out throughput fix). Once a reliable reader matches
  // (`set_acked_frontier(Some(..))`), trimming stops and everything is retained
  // for repair.
  #[test]
  fn volatile_reliable_writer_trimmed_until_reader_matches() {
    let max_retain = 4;
    let buf = WriterSendBuffer::new(
      GUID::GUID_UNKNOWN,
      "t".to_string(),
      /* reliable_writer */ true,
      /* is_builtin */ false,
      /* volatile */ true,
      /* window_limit */ 1000,
      /* backlog_limit */ 1000,
      max_retain,
    );
    // No reliable reader yet: admitted freely (backlog has room) but trimmed to
    // KeepLast so the buffer cannot balloon before discovery completes.
    for _ in 0..100 {
      assert!(admit_now(&buf, WriteOptions::default()));
      assert!(buf.retained_len() <= max_retain);
    }
    assert_eq!(buf.retained_len(), max_retain);

    // A reliable reader matches: from now on the writer retains everything for
    // repair (no trimming), even past max_retain.
    buf.set_acked_frontier(Some(SequenceNumber::new(101)));
    for _ in 0..10 {
      assert!(admit_now(&buf, WriteOptions::default()));
    }
    assert_eq!(buf.retained_len(), max_retain + 10);
  }
}
