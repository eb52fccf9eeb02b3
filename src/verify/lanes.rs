//! Two chunks of a verification in flight: while the device runs one chunk's command buffer,
//! the host records the next. A chunk's recording is host work: 5.0–8.2 µs a hypothesis on
//! this project's 2-core machine (`GpuContext::recording_time`, which bench_verify's grouping
//! table prints, 2026-11-25), with 0.5–1.8 µs more to plan it. Recorded and run one after the
//! other,
//! that adds to every hypothesis' time on a GPU, whose passes for a 10k-triangle model at 256²
//! should take about 10 µs (the compute rasterizer's goal: 100,000 hypotheses a second). So
//! on a GPU a call's chunks go to two lanes, the caller's thread and one more, each taking the
//! next chunk when it is done with its last: each lane has at most one chunk in flight, and
//! the verifier's plan counts the memory of two. A call is then split into a few chunks at
//! least (verifier.rs, `LANE_CHUNKS`), or one chunk's recording would overlap nothing.

use crate::gpu::GpuContext;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

/// Chunks a verification keeps in flight unless the caller says otherwise
/// (`Verifier::with_chunks_in_flight`): 2 on a GPU; 1 on a CPU device such as lavapipe, whose
/// device work runs on the host's own cores, where a second lane only contends with it.
pub(crate) fn default_chunks_in_flight(ctx: &GpuContext) -> usize {
    if ctx.is_cpu() {
        1
    } else {
        2
    }
}

/// Runs `job` on chunks `0..count` in two lanes (the calling thread, and one more where one
/// can be started; else all on the caller's), and hands each chunk's output to `done`, on the
/// calling thread, in chunk order. The first failure, a job's in chunk order or `done`'s,
/// stops the lanes from starting further chunks and is returned; the outputs before it have
/// been handed on. A job that panics stops them too, and its panic goes on in the caller's
/// thread.
pub(crate) fn in_two_lanes<T: Send, E: Send>(
    count: usize,
    job: impl Fn(usize) -> Result<T, E> + Sync,
    mut done: impl FnMut(usize, T) -> Result<(), E>,
) -> Result<(), E> {
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    // The next chunk a lane runs, and its output; none once every chunk is taken or one failed.
    let take = || {
        if failed.load(Ordering::Acquire) {
            return None;
        }
        let chunk = next.fetch_add(1, Ordering::AcqRel);
        if chunk >= count {
            return None;
        }
        // Marks the lanes failed unless the job returns Ok: an Err, or a panic unwinding.
        let stop = StopUnlessDone(&failed);
        let output = job(chunk);
        if output.is_ok() {
            std::mem::forget(stop);
        }
        Some((chunk, output))
    };
    let take = &take;
    std::thread::scope(|scope| {
        // The other lane waits to send a second output until the first is taken: neither
        // lane runs more than a chunk ahead of those handed on, so a call holds the outputs
        // of a few chunks at most.
        let (send, receive) = mpsc::sync_channel(1);
        // Without a second thread, the caller's lane takes every chunk.
        let helper =
            std::thread::Builder::new().name("rangesynth verification lane".into()).spawn_scoped(scope, move || {
                while let Some(ran) = take() {
                    if send.send(ran).is_err() {
                        return;
                    }
                }
            });
        let mut order = InOrder { waiting: (0..count).map(|_| None).collect(), handed: 0 };
        let handed = (|| {
            // The caller's lane, handing on what is ready before each of its chunks.
            loop {
                for (chunk, output) in receive.try_iter() {
                    order.waiting[chunk] = Some(output);
                }
                order.hand_on(&mut done)?;
                // Two chunks taken and not handed on: the other lane's is next; wait for it.
                if next.load(Ordering::Acquire) >= order.handed + 2 {
                    if let Ok((chunk, output)) = receive.recv() {
                        order.waiting[chunk] = Some(output);
                        continue;
                    }
                }
                let Some((chunk, output)) = take() else { break };
                order.waiting[chunk] = Some(output);
            }
            // The other lane's last chunks.
            for (chunk, output) in receive {
                order.waiting[chunk] = Some(output);
                order.hand_on(&mut done)?;
            }
            Ok(())
        })();
        if handed.is_err() {
            // `done` may have failed with the other lane still running: it starts no more.
            failed.store(true, Ordering::Release);
            return handed;
        }
        // A panic in the other lane goes on here, as it would have in one lane.
        if let Ok(Err(panic)) = helper.map(|lane| lane.join()) {
            std::panic::resume_unwind(panic);
        }
        Ok(())
    })
}

/// Sets the flag when dropped: forgotten once a job succeeds.
struct StopUnlessDone<'a>(&'a AtomicBool);

impl Drop for StopUnlessDone<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
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
    use super::in_two_lanes;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::{Duration, Instant};

    #[test]
    fn outputs_come_in_chunk_order_from_two_threads_at_once() {
        // Chunks 0 and 1 each wait, up to 10 s, until both are running: in one lane they
        // cannot be, and the first fails.
        let inside = AtomicUsize::new(0);
        let mut handed = Vec::new();
        let result = in_two_lanes(
            6,
            |chunk| {
                if chunk < 2 {
                    inside.fetch_add(1, Ordering::SeqCst);
                    let start = Instant::now();
                    while inside.load(Ordering::SeqCst) < 2 {
                        if start.elapsed() > Duration::from_secs(10) {
                            return Err(format!("chunk {chunk} ran alone"));
                        }
                        std::thread::sleep(Duration::from_millis(1));
                    }
                }
                Ok(chunk * 10)
            },
            |chunk, output| {
                handed.push((chunk, output));
                Ok(())
            },
        );
        assert_eq!(result, Ok(()));
        assert_eq!(handed, (0..6).map(|c| (c, c * 10)).collect::<Vec<_>>());
    }

    #[test]
    fn no_lane_runs_far_ahead_of_a_slow_chunk() {
        // While chunk 0 takes 200 ms, the other lane may run a chunk and hold one more
        // output: chunks 0 to 3 have started by its end, not the other 96.
        let started = AtomicUsize::new(0);
        let started_by_the_end_of_0 = AtomicUsize::new(0);
        let result: Result<(), ()> = in_two_lanes(
            100,
            |chunk| {
                started.fetch_add(1, Ordering::SeqCst);
                if chunk == 0 {
                    std::thread::sleep(Duration::from_millis(200));
                    started_by_the_end_of_0.store(started.load(Ordering::SeqCst), Ordering::SeqCst);
                }
                Ok(chunk)
            },
            |_, _| Ok(()),
        );
        assert_eq!(result, Ok(()));
        let ahead = started_by_the_end_of_0.load(Ordering::SeqCst);
        assert!(ahead <= 4, "{ahead} chunks had started when chunk 0 ended");
    }

    #[test]
    fn the_first_failure_in_chunk_order_stops_the_lanes() {
        // Every chunk takes a millisecond, so the lanes learn of chunk 3's failure long before
        // they could run the other 96.
        let started = AtomicUsize::new(0);
        let mut handed = Vec::new();
        let result = in_two_lanes(
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
        let result = in_two_lanes(
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
            in_two_lanes(
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
}
