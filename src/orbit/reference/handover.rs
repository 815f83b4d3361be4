//! The meeting point of the threads that share each step of a wide reference orbit (a
//! team: the caller and its helpers, [`super::fixed`], [`super::team`]), and the caller's
//! rule for when to stop sharing because the machine is busy.
//!
//! Each thread publishes its part of a step in a box and waits for everyone else's. When all
//! have a core the others answer within a microsecond or two, so the wait spins; but where
//! the machine is busier than its cores (another render, a compiler, a fuzzer), a partner
//! is often descheduled, and every step then waits for it to be scheduled again: the e1086
//! benchmark's orbit took 17–22 s shared against 1.7 s on one thread beside Fraktaler-3
//! rendering on both cores of a 2-core machine. So the caller watches its waits
//! ([`Contention`]): when a few steps in a short window had to give up the core before the
//! helpers answered, it sends them to sleep and steps alone for a while (four times
//! longer each time sharing fails again, shorter again after clean stretches of sharing),
//! then wakes them with its current value ([`Resync`]). The steps are the same bits on one thread or two, so neither the switch
//! nor its timing changes the orbit.
//!
//! Every switch starts a new epoch. A step's publication carries the epoch with the step
//! number ([`Shared::publish`]), so no thread ever takes another's work from an earlier
//! epoch: a helper that slept through a pause and a resume finds the epoch moved on,
//! drops what it was doing and takes the caller's value from the latest [`Resync`].

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};

/// Spins before a wait starts giving up the core between looks (tens of microseconds; with
/// 16384 the e1086 orbit beside two busy loops took 5–12 s against 6–8 s, alternating
/// runs).
const SPINS: u32 = 1 << 10;
/// Shared steps per window of [`Contention`].
const WINDOW: u32 = 64;
/// Slow waits within a window that make the caller stop sharing (each can cost a
/// scheduler's time slice, milliseconds, so few are let through).
const SLOW_LIMIT: u32 = 2;
/// The shortest and longest stretch of steps the caller takes alone before trying again
/// (at 3700 bits, about 2 ms and 0.5 s on a 2-core machine), and the factor between one
/// stretch and the next while sharing keeps failing.
const ALONE_MIN: u32 = 1 << 10;
const ALONE_MAX: u32 = 1 << 18;
const ALONE_GROWTH: u32 = 4;
/// Clean windows after which the stretch alone shrinks by [`ALONE_GROWTH`].
const CLEAN_SHRINK: u32 = 16;
/// Bits of a published value that hold the step number (the epoch is above them).
const SEQ_BITS: u32 = 40;

/// Spins until `ready`, then gives up the core between looks; true when it had to give it
/// up (a slow wait: the other thread was not running).
pub fn wait(ready: impl Fn() -> bool) -> bool {
    let mut spins = 0;
    while !ready() {
        if spins < SPINS {
            spins += 1;
            std::hint::spin_loop();
        } else {
            spins += 1;
            std::thread::yield_now();
        }
    }
    spins > SPINS
}

/// A value alone on its cache lines (the threads' step counters would otherwise share one,
/// and every store to any would take it from the readers of the others).
#[repr(align(128))]
struct Line<T>(T);

/// The caller's value after a step, for a helper that rejoins in a new epoch.
#[derive(Debug, Default)]
pub struct Resync {
    /// The epoch the helper joins.
    pub epoch: u64,
    /// The steps the value has taken.
    pub seq: u64,
    /// Its real part, as the orbit stores it.
    pub x: Vec<u64>,
    /// Its imaginary part.
    pub y: Vec<u64>,
}

/// What a team's threads share: each publishes its words of a step in one of two boxes (by
/// the step's parity: a box is written again two steps later, after all its readers have
/// answered the step between), and the epoch and number of the last step it published.
pub struct Shared {
    /// By thread (0 the caller, then the helpers), then by the step's parity.
    pub boxes: Vec<[Vec<AtomicU64>; 2]>,
    done: Vec<Line<AtomicU64>>,
    /// The caller's epoch.
    epoch: AtomicU64,
    stop: AtomicBool,
    resync: Mutex<Resync>,
    wake: Condvar,
}

impl Shared {
    /// For a team of `threads` threads, boxes of `words` words each.
    pub fn new(threads: usize, words: usize) -> Shared {
        let boxes = || (0..words).map(|_| AtomicU64::new(0)).collect();
        Shared {
            boxes: (0..threads).map(|_| [boxes(), boxes()]).collect(),
            done: (0..threads).map(|_| Line(AtomicU64::new(0))).collect(),
            epoch: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            resync: Mutex::new(Resync::default()),
            wake: Condvar::new(),
        }
    }

    /// Thread `me` has filled its box for step `seq` of `epoch`.
    pub fn publish(&self, me: usize, epoch: u64, seq: u64) {
        self.done[me].0.store(epoch << SEQ_BITS | seq, Ordering::Release);
    }

    /// Whether thread `who` has published step `seq` of `epoch` (or a later step of it).
    pub fn has(&self, who: usize, epoch: u64, seq: u64) -> bool {
        let v = self.done[who].0.load(Ordering::Acquire);
        v >> SEQ_BITS == epoch && v & ((1 << SEQ_BITS) - 1) >= seq
    }

    /// Whether every thread but `me` has published step `seq` of `epoch`.
    pub fn others_have(&self, me: usize, epoch: u64, seq: u64) -> bool {
        (0..self.done.len()).all(|who| who == me || self.has(who, epoch, seq))
    }

    /// Whether a helper of `epoch` should leave its step: the caller has stopped, or paused
    /// or resumed since.
    pub fn left(&self, epoch: u64) -> bool {
        self.stop.load(Ordering::Acquire) || self.epoch.load(Ordering::Acquire) != epoch
    }

    /// The caller stops sharing for now: a new epoch, in which the helpers have no part.
    pub fn pause(&self) -> u64 {
        self.epoch.fetch_add(1, Ordering::AcqRel) + 1
    }

    /// The caller shares again from its value `(x, y)` after `seq` steps: a new epoch, which
    /// the helpers join with that value. Returns the epoch.
    pub fn resume(&self, seq: u64, x: &[u64], y: &[u64]) -> u64 {
        let mut r = self.resync.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let epoch = self.epoch.fetch_add(1, Ordering::AcqRel) + 1;
        r.epoch = epoch;
        r.seq = seq;
        r.x.clear();
        r.x.extend_from_slice(x);
        r.y.clear();
        r.y.extend_from_slice(y);
        drop(r);
        self.wake.notify_all();
        epoch
    }

    /// For a helper that has left epoch `epoch`: sleeps until the caller resumes, then hands
    /// `take` the latest [`Resync`] and returns its epoch; None once the caller has stopped.
    pub fn rejoin(&self, epoch: u64, take: impl FnOnce(&Resync)) -> Option<u64> {
        let mut r = self.resync.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        loop {
            if self.stop.load(Ordering::Acquire) {
                return None;
            }
            if r.epoch > epoch {
                take(&r);
                return Some(r.epoch);
            }
            r = self.wake.wait(r).unwrap_or_else(std::sync::PoisonError::into_inner);
        }
    }

    /// Stops the helpers for good, waking those that sleep.
    pub fn stop(&self) {
        let r = self.resync.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        self.stop.store(true, Ordering::Release);
        drop(r);
        self.wake.notify_all();
    }
}

/// Stops the helpers when dropped (however the caller's work ends, a panic too: the scope
/// would otherwise wait for helpers waiting for a step that never comes).
pub struct StopOnDrop<'a>(pub &'a Shared);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.stop();
    }
}

/// The caller's rule for when to stop sharing: counts the slow waits of each window of
/// `WINDOW` shared steps, and stops sharing at the `SLOW_LIMIT`th, for a stretch alone
/// that grows by `ALONE_GROWTH` each time (from `ALONE_MIN` to `ALONE_MAX` steps) and
/// shrinks by as much after every `CLEAN_SHRINK` windows without a stop. On a machine that
/// stays busy, a few tries bring the stretch to its longest, so that sharing is tried again
/// only about twice a second; on one that is busy now and then, it comes back down.
#[derive(Debug, Clone, Copy)]
pub struct Contention {
    steps: u32,
    slow: u32,
    clean: u32,
    alone: u32,
}

impl Default for Contention {
    fn default() -> Self {
        Contention { steps: 0, slow: 0, clean: 0, alone: ALONE_MIN }
    }
}

impl Contention {
    /// After a shared step whose wait was `slow` or not: the steps to take alone now, if
    /// sharing should stop.
    pub fn after(&mut self, slow: bool) -> Option<u32> {
        self.steps += 1;
        self.slow += u32::from(slow);
        if self.slow >= SLOW_LIMIT {
            let alone = self.alone;
            self.alone = (self.alone * ALONE_GROWTH).min(ALONE_MAX);
            *self = Contention { steps: 0, slow: 0, clean: 0, ..*self };
            return Some(alone);
        }
        if self.steps == WINDOW {
            self.steps = 0;
            self.slow = 0;
            self.clean += 1;
            if self.clean >= CLEAN_SHRINK {
                self.clean = 0;
                self.alone = (self.alone / ALONE_GROWTH).max(ALONE_MIN);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sharing_stops_at_the_slow_limit_for_ever_longer_stretches() {
        let mut c = Contention::default();
        // Occasional slow waits (fewer than the limit in any window) never stop it.
        for k in 0..10 * WINDOW {
            assert_eq!(c.after(k % WINDOW == 0), None, "step {k}");
        }
        // A busy machine: every wait slow.
        let mut stretches = vec![];
        for _ in 0..8 {
            let stops: Vec<u32> = (0..SLOW_LIMIT).filter_map(|_| c.after(true)).collect();
            stretches.extend(stops);
        }
        assert_eq!(stretches.len(), 8);
        assert_eq!(stretches[0], ALONE_MIN);
        assert!(stretches.windows(2).all(|w| w[1] == (w[0] * ALONE_GROWTH).min(ALONE_MAX)), "{stretches:?}");
        assert_eq!(*stretches.last().unwrap(), ALONE_MAX);
        // Each clean stretch brings it down a step, to the shortest at most.
        let mut next = ALONE_MAX;
        for _ in 0..8 {
            for _ in 0..CLEAN_SHRINK * WINDOW {
                assert_eq!(c.after(false), None);
            }
            next = (next / ALONE_GROWTH).max(ALONE_MIN);
            let again: Vec<u32> = (0..SLOW_LIMIT).filter_map(|_| c.after(true)).collect();
            assert_eq!(again, [next]);
            // That stop grew it again; the next clean stretch takes it back to `next`.
            for _ in 0..CLEAN_SHRINK * WINDOW {
                assert_eq!(c.after(false), None);
            }
        }
        assert_eq!(next, ALONE_MIN);
    }

    #[test]
    fn publications_count_only_in_their_own_epoch() {
        let sh = Shared::new(3, 1);
        sh.publish(1, 0, 5);
        assert!(sh.has(1, 0, 5) && sh.has(1, 0, 3) && !sh.has(1, 0, 6));
        // Thread 0 waits for both helpers, each helper for the other and the caller.
        assert!(!sh.others_have(0, 0, 5));
        sh.publish(2, 0, 5);
        assert!(sh.others_have(0, 0, 5) && !sh.others_have(1, 0, 5));
        sh.publish(0, 0, 5);
        assert!(sh.others_have(1, 0, 5) && sh.others_have(2, 0, 4));
        // A helper's late publication from an earlier epoch never answers the caller.
        let e = sh.pause();
        assert!(sh.left(0) && !sh.left(e));
        assert!(!sh.has(1, e, 1));
        let e2 = sh.resume(9, &[1, 2], &[3]);
        assert!(e2 > e && sh.left(e));
        let mut got = (0, vec![], vec![]);
        let joined = sh.rejoin(0, |r| got = (r.seq, r.x.clone(), r.y.clone()));
        assert_eq!(joined, Some(e2));
        assert_eq!(got, (9, vec![1, 2], vec![3]));
        sh.stop();
        assert_eq!(sh.rejoin(e2, |_| {}), None);
    }
}
