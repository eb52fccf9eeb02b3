//! Several chunks of a verification in flight: while the device runs one chunk's command buffer,
//! the host records the next. A chunk's recording is host work, which on a fast GPU takes as
//! long as the device's work or longer (`GpuContext::recording_time`, which bench_verify's
//! grouping table prints; figures in docs/performance-history.md). Recorded and run one after
//! the other, that adds to every hypothesis' time. So on a GPU a call's chunks go to lanes, the
//! caller's thread and more, each taking the next chunk when it is done with its last: each
//! lane has at most one chunk in flight, and the verifier's plan counts the memory of one chunk
//! a lane. A call is then split into a few chunks a lane at least, or one chunk's recording
//! would overlap nothing, and its first chunks are shorter, so that the device starts sooner
//! (`lane_chunk_cap`). No lane starts a chunk two a lane past the outputs handed on, so a call
//! holds a few chunks' outputs at a time, however slow one of them is.

use crate::gpu::GpuContext;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Condvar, Mutex};

/// Most chunks a verification may keep in flight (`Verifier::with_chunks_in_flight`): the
/// render target pool keeps their slots' targets (src/render/target_pool.rs).
pub use crate::render::MAX_CHUNKS_IN_FLIGHT;

/// Chunks a verification keeps in flight unless the caller says otherwise
/// (`Verifier::with_chunks_in_flight`): 3 on a GPU, where a third lane gains over two for
/// every model measured and a fourth gains for some but loses for a dense one; 1 on a CPU
/// device such as lavapipe, whose device work runs on the host's own cores, where a second lane
/// only contends with it.
pub(crate) fn default_chunks_in_flight(ctx: &GpuContext) -> usize {
    if ctx.is_cpu() {
        1
    } else {
        3
    }
}

/// Chunks a call is split into, at least, a lane: with two, all but the first one's recording
/// (a quarter of the host's work) overlaps the device's work.
const LANE_CHUNKS: usize = 2;
/// Fewest hypotheses in a chunk run in lanes: a chunk's own set-up (its slots, counts and
/// readback, one submission and wait) is paid over at least this many.
const MIN_LANE_CHUNK: usize = 64;
/// The first chunks of a call in lanes ramp up to the cap in this many steps: chunk k holds at
/// most (k + 1) eighths of it. The lanes start their first chunks together, and the device
/// waits until the first of them is recorded, which on a GPU takes longer than running it.
/// Short first chunks start the device sooner, and each next one is recorded while the device
/// runs those before it; the longer the call, the less it gains.
const RAMP_STEPS: usize = 8;

/// The most hypotheses chunk number `chunk` of a call of `hypotheses` may hold where it runs
/// in `lanes` lanes (at least two), `cap` the most a chunk may hold: a call of one chunk would
/// overlap nothing, so it goes in [`LANE_CHUNKS`] chunks a lane at least, and its first chunks
/// ramp up to the cap ([`RAMP_STEPS`]); none is cut below [`MIN_LANE_CHUNK`].
pub(crate) fn lane_chunk_cap(cap: usize, hypotheses: usize, lanes: usize, chunk: usize) -> usize {
    let cap = cap.min(hypotheses.div_ceil(LANE_CHUNKS * lanes).max(MIN_LANE_CHUNK));
    let ramp = cap.saturating_mul(chunk.saturating_add(1)) / RAMP_STEPS;
    cap.min(ramp.max(MIN_LANE_CHUNK))
}

/// Runs `job` on chunks `0..count` in `lanes` lanes (the calling thread, and one more thread
/// a lane where it can be started; else fewer, down to the caller's alone), and hands each
/// chunk's output to `done`, on the calling thread, in chunk order. The first failure, a
/// job's in chunk order or `done`'s, stops the lanes from starting further chunks and is
/// returned; the outputs before it have been handed on. A job or a `done` that panics stops
/// them too, and the panic goes on in the caller's thread.
pub(crate) fn in_lanes<T: Send, E: Send>(
    lanes: usize,
    count: usize,
    job: impl Fn(usize) -> Result<T, E> + Sync,
    mut done: impl FnMut(usize, T) -> Result<(), E>,
) -> Result<(), E> {
    let shared = Shared::default();
    // How far ahead of the outputs handed on a lane may start a chunk: a call holds the outputs
    // of a few chunks a lane at most, however slow one chunk is.
    let window = 2 * lanes.max(1);
    // Runs a chunk taken (every chunk taken is run, so that no output the caller waits for is
    // lost), and stops the lanes unless the job returns Ok: an Err, or a panic unwinding.
    let run = |chunk: usize| {
        let stop = StopOnDrop(&shared);
        let output = job(chunk);
        if output.is_ok() {
            std::mem::forget(stop);
        }
        (chunk, output)
    };
    let (run, shared) = (&run, &shared);
    std::thread::scope(|scope| {
        // The other lanes wait to send a second output until their first is taken.
        let (send, receive) = mpsc::sync_channel(lanes.saturating_sub(1));
        // Where a thread cannot be started, the lanes that could take every chunk.
        let helpers: Vec<_> = (1..lanes.max(1))
            .filter_map(|_| {
                let send = send.clone();
                let lane = move || {
                    while let Some(chunk) = shared.take(count) {
                        shared.wait_for_window(chunk, window);
                        if send.send(run(chunk)).is_err() {
                            return;
                        }
                    }
                };
                std::thread::Builder::new().name(LANE_THREAD.into()).spawn_scoped(scope, lane).ok()
            })
            .collect();
        // The receiver ends once every other lane has.
        drop(send);
        let running = 1 + helpers.len();
        // However the caller's lane ends (an error, or a panic in `done`), the others stop
        // rather than wait for outputs that will not be handed on.
        let _stop = StopOnDrop(shared);
        let mut order = InOrder { waiting: (0..count).map(|_| None).collect(), handed: 0 };
        let mut hand_on = |order: &mut InOrder<T, E>| {
            let result = order.hand_on(&mut done);
            shared.handed_on(order.handed);
            result
        };
        let handed = (|| {
            // The caller's lane, handing on what is ready before each of its chunks, and taking
            // one only while fewer than a chunk a lane are taken and not handed on; else another
            // lane's is next: it waits for it.
            loop {
                for (chunk, output) in receive.try_iter() {
                    order.waiting[chunk] = Some(output);
                }
                hand_on(&mut order)?;
                match shared.take_below(count, order.handed + running) {
                    Take::Chunk(chunk) => {
                        let (chunk, output) = run(chunk);
                        order.waiting[chunk] = Some(output);
                    }
                    Take::Later => match receive.recv() {
                        Ok((chunk, output)) => order.waiting[chunk] = Some(output),
                        Err(_) => break,
                    },
                    Take::Nothing => break,
                }
            }
            // The other lanes' last chunks.
            for (chunk, output) in receive {
                order.waiting[chunk] = Some(output);
                hand_on(&mut order)?;
            }
            Ok(())
        })();
        // A failure (`done`'s, or a job's) may have come with other lanes still running: they
        // start no more, and each ends (the receiver is gone) before the call returns.
        shared.stop();
        let mut panicked = None;
        for helper in helpers {
            if let Err(panic) = helper.join() {
                panicked.get_or_insert(panic);
            }
        }
        // The failure handed on comes first in chunk order: a chunk whose job panicked was
        // never handed on. Else a panic in another lane goes on here, as it would have in one.
        handed?;
        if let Some(panic) = panicked {
            std::panic::resume_unwind(panic);
        }
        debug_assert_eq!(order.handed, count, "every output was handed on");
        Ok(())
    })
}

/// The name of the threads of the lanes beside the caller's.
const LANE_THREAD: &str = "rangesynth verification lane";

/// What the lanes share: the next chunk to take, whether they stop, and how many outputs the
/// caller's lane has handed on, which the other lanes wait on to start a chunk.
#[derive(Default)]
struct Shared {
    next: AtomicUsize,
    failed: AtomicBool,
    handed: Mutex<usize>,
    moved: Condvar,
}

/// What the caller's lane may take.
enum Take {
    Chunk(usize),
    /// Nothing yet: as many chunks are taken and not handed on as there are lanes.
    Later,
    /// Nothing: every chunk is taken, or the lanes stopped.
    Nothing,
}

impl Shared {
    /// The next of `count` chunks for a lane beside the caller's; none once every chunk is
    /// taken or the lanes stopped.
    fn take(&self, count: usize) -> Option<usize> {
        if self.failed.load(Ordering::Acquire) {
            return None;
        }
        Some(self.next.fetch_add(1, Ordering::AcqRel)).filter(|&chunk| chunk < count)
    }

    /// The next of `count` chunks for the caller's lane, if it lies below `limit`.
    fn take_below(&self, count: usize, limit: usize) -> Take {
        loop {
            let chunk = self.next.load(Ordering::Acquire);
            if self.failed.load(Ordering::Acquire) || chunk >= count {
                return Take::Nothing;
            }
            if chunk >= limit {
                return Take::Later;
            }
            if self.next.compare_exchange(chunk, chunk + 1, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                return Take::Chunk(chunk);
            }
        }
    }

    /// Waits until `chunk` lies within `window` chunks of the outputs handed on, or the lanes
    /// stop.
    fn wait_for_window(&self, chunk: usize, window: usize) {
        let mut handed = self.handed.lock().unwrap_or_else(|p| p.into_inner());
        while chunk >= *handed + window && !self.failed.load(Ordering::Acquire) {
            handed = self.moved.wait(handed).unwrap_or_else(|p| p.into_inner());
        }
    }

    /// `handed` outputs have been handed on.
    fn handed_on(&self, handed: usize) {
        *self.handed.lock().unwrap_or_else(|p| p.into_inner()) = handed;
        self.moved.notify_all();
    }

    /// Stops the lanes: none takes a chunk after this, and none waits to start one.
    fn stop(&self) {
        self.failed.store(true, Ordering::Release);
        // Under the lock, so that a lane between its test of the flag and its wait is woken.
        let _handed = self.handed.lock().unwrap_or_else(|p| p.into_inner());
        self.moved.notify_all();
    }
}

/// Stops the lanes when dropped (forgotten where they go on).
struct StopOnDrop<'a>(&'a Shared);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.stop();
    }
}

/// Outputs that came before the ones ahead of them in chunk order, and how many were handed on.
struct InOrder<T, E> {
    waiting: Vec<Option<Result<T, E>>>,
    handed: usize,
}

impl<T, E> InOrder<T, E> {
    /// Hands on the outputs now next in chunk order, up to the first failure, a job's or
    /// `done`'s, which it returns.
    fn hand_on(&mut self, done: &mut impl FnMut(usize, T) -> Result<(), E>) -> Result<(), E> {
        while let Some(output) = self.waiting.get_mut(self.handed).and_then(Option::take) {
            done(self.handed, output?)?;
            self.handed += 1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{in_lanes, lane_chunk_cap, LANE_THREAD};
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    use std::time::{Duration, Instant};

    #[test]
    fn outputs_come_in_chunk_order_from_as_many_threads_at_once_as_lanes() {
        for lanes in [2, 4] {
            // Chunks 0 to lanes - 1 each wait until all of them are running: in fewer lanes they
            // cannot be, and the first fails (after the hang guard's minute).
            let inside = AtomicUsize::new(0);
            let mut handed = Vec::new();
            let result: Result<(), String> = in_lanes(
                lanes,
                3 * lanes,
                |chunk| {
                    if chunk < lanes {
                        inside.fetch_add(1, Ordering::SeqCst);
                        let all_inside = || inside.load(Ordering::SeqCst) >= lanes;
                        wait_until(all_inside, &format!("chunk {chunk} of {lanes} lanes waiting for the others"))?;
                    }
                    Ok(chunk * 10)
                },
                |chunk, output| {
                    handed.push((chunk, output));
                    Ok(())
                },
            );
            assert_eq!(result, Ok(()));
            assert_eq!(handed, (0..3 * lanes).map(|c| (c, c * 10)).collect::<Vec<_>>());
        }
    }

    /// Waits until `ready`, or fails after a minute (a hang guard, never the thing tested).
    fn wait_until(ready: impl Fn() -> bool, what: &str) -> Result<(), String> {
        let start = Instant::now();
        while !ready() {
            if start.elapsed() > Duration::from_secs(60) {
                return Err(format!("{what}: not after 60 s"));
            }
            std::thread::yield_now();
        }
        Ok(())
    }

    #[test]
    fn no_lane_runs_far_ahead_of_a_slow_chunk() {
        for lanes in [2, 3, 4] {
            // The first chunk a lane beside the caller's runs is held until every chunk that
            // may start meanwhile has started: the other lanes run as far ahead of it as they
            // may. No chunk may start a window (two a lane) or more past the outputs handed
            // on, which cannot pass the held chunk's. With two lanes only the caller's runs
            // meanwhile, and it takes a chunk only while fewer than one a lane are taken and
            // not handed on.
            let window = 2 * lanes;
            let reachable = if lanes == 2 { lanes } else { window };
            let (handed, started) = (AtomicUsize::new(0), AtomicUsize::new(0));
            let slow = Mutex::new(None);
            let a_lane_started = std::sync::atomic::AtomicBool::new(false);
            let result: Result<(), String> = in_lanes(
                lanes,
                100,
                |chunk| {
                    let handed_then = handed.load(Ordering::SeqCst);
                    if chunk >= handed_then + window {
                        return Err(format!("{lanes} lanes: chunk {chunk} started with {handed_then} handed on"));
                    }
                    started.fetch_add(1, Ordering::SeqCst);
                    let on_a_lane = std::thread::current().name() == Some(LANE_THREAD);
                    if on_a_lane {
                        a_lane_started.store(true, Ordering::SeqCst);
                    } else {
                        // So that the caller's lane cannot run every chunk before another
                        // lane is scheduled.
                        wait_until(|| a_lane_started.load(Ordering::SeqCst), "another lane starting")?;
                    }
                    if on_a_lane && *slow.lock().unwrap().get_or_insert(chunk) == chunk {
                        let all_started = || started.load(Ordering::SeqCst) >= chunk + reachable;
                        wait_until(all_started, &format!("{lanes} lanes: the chunks up to {chunk} + {reachable}"))?;
                    }
                    Ok(chunk)
                },
                |_, _| {
                    handed.fetch_add(1, Ordering::SeqCst);
                    Ok(())
                },
            );
            assert_eq!(result, Ok(()));
            assert!(slow.lock().unwrap().is_some(), "a lane beside the caller's ran a chunk");
        }
    }

    #[test]
    fn the_first_failure_in_chunk_order_stops_the_lanes() {
        // Every chunk takes a millisecond, so the lanes learn of chunk 3's failure long before
        // they could run the other 96.
        let started = AtomicUsize::new(0);
        let mut handed = Vec::new();
        let result = in_lanes(
            2,
            100,
            |chunk| {
                started.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(1));
                if chunk == 3 {
                    Err(chunk)
                } else {
                    Ok(chunk)
                }
            },
            |chunk, _| {
                handed.push(chunk);
                Ok(())
            },
        );
        assert_eq!(result, Err(3));
        assert_eq!(handed, [0, 1, 2]);
        assert!(started.load(Ordering::Relaxed) < 50, "{} chunks started", started.load(Ordering::Relaxed));
    }

    #[test]
    fn a_failure_to_take_an_output_stops_the_lanes() {
        let started = AtomicUsize::new(0);
        let result = in_lanes(
            2,
            100,
            |chunk| -> Result<usize, usize> {
                started.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(1));
                Ok(chunk)
            },
            |chunk, _| if chunk == 2 { Err(1000 + chunk) } else { Ok(()) },
        );
        assert_eq!(result, Err(1002));
        assert!(started.load(Ordering::Relaxed) < 50, "{} chunks started", started.load(Ordering::Relaxed));
    }

    #[test]
    fn a_panicking_chunk_stops_the_lanes_and_goes_on_in_the_caller() {
        // The lanes learn of the panic once the panic hook has run (printing a backtrace can
        // take tens of milliseconds) and the unwinding begins: chunks of 20 ms leave room.
        let started = AtomicUsize::new(0);
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            in_lanes(
                2,
                100,
                |chunk| -> Result<usize, ()> {
                    started.fetch_add(1, Ordering::Relaxed);
                    std::thread::sleep(Duration::from_millis(20));
                    assert!(chunk != 3, "chunk 3 panics");
                    Ok(chunk)
                },
                |_, _| Ok(()),
            )
        }));
        let panic = outcome.expect_err("the panic goes on");
        let message = panic.downcast_ref::<String>().map(String::as_str).or(panic.downcast_ref::<&str>().copied());
        assert_eq!(message, Some("chunk 3 panics"));
        assert!(started.load(Ordering::Relaxed) < 50, "{} chunks started", started.load(Ordering::Relaxed));
    }

    #[test]
    fn a_panic_taking_an_output_goes_on_in_the_caller_and_stops_the_lanes() {
        // Lanes beside the caller's wait for their window while `done` panics: they must be
        // woken, or the call never ends. Run on a thread of its own, so that a call that hangs
        // fails the test after 10 s instead of hanging it.
        let (finished, outcome) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let caught = std::panic::catch_unwind(|| {
                in_lanes(
                    3,
                    100,
                    |chunk| -> Result<usize, ()> {
                        std::thread::sleep(Duration::from_millis(1));
                        Ok(chunk)
                    },
                    |chunk, _| {
                        assert!(chunk != 2, "taking chunk 2 panics");
                        Ok(())
                    },
                )
            });
            let _ = finished.send(caught.is_err());
        });
        let panicked = outcome.recv_timeout(Duration::from_secs(10)).expect("the call ended");
        assert!(panicked, "the panic went on in the caller");
    }

    #[test]
    fn an_earlier_failure_is_returned_though_a_later_chunk_panicked() {
        // Chunk 0 fails after 50 ms; meanwhile the lanes beside the caller's panic at whatever
        // later chunk they run. The failure comes first in chunk order: it is returned, not
        // the panic, nor the scope's "a scoped thread panicked" for a lane never joined.
        let result = in_lanes(
            3,
            100,
            |chunk| {
                if chunk == 0 {
                    std::thread::sleep(Duration::from_millis(50));
                    return Err(chunk);
                }
                assert!(std::thread::current().name() != Some(LANE_THREAD), "a later chunk panics");
                Ok(chunk)
            },
            |_, _| Ok(()),
        );
        assert_eq!(result, Err(0));
    }

    #[test]
    fn a_call_in_lanes_ramps_its_first_chunks_up_to_the_cap() {
        // Six chunks' worth in three lanes: 128, 256, … 1,024 from the eighth chunk on.
        let caps: Vec<usize> = (0..10).map(|chunk| lane_chunk_cap(1024, 6144, 3, chunk)).collect();
        assert_eq!(caps, [128, 256, 384, 512, 640, 768, 896, 1024, 1024, 1024]);
        // A short call: two chunks a lane at least (2,048 in three lanes: 342 a chunk), its
        // first chunks no shorter than 64.
        let caps: Vec<usize> = (0..9).map(|chunk| lane_chunk_cap(1024, 2048, 3, chunk)).collect();
        assert_eq!(caps, [64, 85, 128, 171, 213, 256, 299, 342, 342]);
        // A cap under 64 (the caller's chunk size, or shadow mode `exact`'s 16) holds throughout.
        assert!((0..10).all(|chunk| lane_chunk_cap(16, 6144, 3, chunk) == 16));
        // Chunk numbers past any call's do not overflow.
        assert_eq!(lane_chunk_cap(1024, usize::MAX, 4, usize::MAX), 1024);
    }
}
