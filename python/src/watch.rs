//! How a long call talks to Python while it runs. The work runs on a thread of its own (on the
//! call's worker pool, if it has one), never holding the interpreter; the calling thread waits,
//! the interpreter free, and every [`LOOK_EVERY`] takes it briefly to hand the newest progress
//! to the progress callable and to run Python's pending signal handlers. Signals are only
//! handled on Python's main thread, which is why the calling thread does it, not the work: a
//! `KeyboardInterrupt` (Ctrl-C) or an exception of the callable raises the stop flag, which the
//! work sees at its next step, as the command line's Ctrl-C flag.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;
use thermostamp::experiment::sheet_test::Progress;

/// How often the calling thread looks at Python.
const LOOK_EVERY: Duration = Duration::from_millis(100);

/// What the work and the calling thread share: the newest progress and the stop flag.
#[derive(Default)]
pub struct Beacon {
    /// `(fraction of the end time, step, process time)`, taken by the calling thread.
    newest: Mutex<Option<(f64, usize, f64)>>,
    stop: AtomicBool,
}

/// The [`Progress`] of a solver run: each step's progress left in the beacon, the stop flag read.
pub struct Watch<'a> {
    beacon: &'a Beacon,
    end_time: f64,
    time_scaling: f64,
}

impl<'a> Watch<'a> {
    pub fn new(beacon: &'a Beacon, end_time: f64, time_scaling: f64) -> Self {
        Self {
            beacon,
            end_time,
            time_scaling,
        }
    }
}

impl Progress for Watch<'_> {
    fn update(&mut self, time: f64, step: usize) {
        let fraction = (time / self.end_time).clamp(0.0, 1.0);
        let newest = (fraction, step, time * self.time_scaling);
        *self.beacon.newest.lock().unwrap_or_else(|e| e.into_inner()) = Some(newest);
    }

    fn interrupted(&self) -> bool {
        self.beacon.stop.load(Ordering::Relaxed)
    }
}

/// Runs `work` on a thread of its own (inside `pool` when given) while this thread hands its
/// progress to `callback` as `callback(fraction, step, time)` and honours Ctrl-C; returns what
/// `work` returned and the exception that stopped it, if one did.
pub fn supervise<T: Send>(
    py: Python<'_>,
    pool: Option<&rayon::ThreadPool>,
    callback: Option<&Py<PyAny>>,
    work: impl FnOnce(&Beacon) -> T + Send,
) -> (T, Option<PyErr>) {
    let beacon = Beacon::default();
    let ended = (Mutex::new(false), Condvar::new());
    std::thread::scope(|scope| {
        let (beacon, ended) = (&beacon, &ended);
        let worker = scope.spawn(move || {
            // the flag is raised however the work ends, a panic too
            let _end = EndFlag(ended);
            match pool {
                Some(pool) => pool.install(|| work(beacon)),
                None => work(beacon),
            }
        });
        let mut raised: Option<PyErr> = None;
        loop {
            let done = py.detach(|| wait_for_end(ended));
            if raised.is_none() {
                raised = look_at_python(py, beacon, callback);
                if raised.is_some() {
                    beacon.stop.store(true, Ordering::Relaxed);
                }
            }
            if done {
                break;
            }
        }
        let value = py.detach(|| worker.join());
        match value {
            Ok(value) => (value, raised),
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}

/// Raises the end flag when dropped.
struct EndFlag<'a>(&'a (Mutex<bool>, Condvar));

impl Drop for EndFlag<'_> {
    fn drop(&mut self) {
        *self.0 .0.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.0 .1.notify_all();
    }
}

/// Whether the work has ended, waiting for it [`LOOK_EVERY`] at most.
fn wait_for_end((flag, changed): &(Mutex<bool>, Condvar)) -> bool {
    let ended = flag.lock().unwrap_or_else(|e| e.into_inner());
    let (ended, _) = changed
        .wait_timeout_while(ended, LOOK_EVERY, |ended| !*ended)
        .unwrap_or_else(|e| e.into_inner());
    *ended
}

/// Runs Python's pending signal handlers, then hands the newest progress to the callable; the
/// exception either raised.
fn look_at_python(py: Python<'_>, beacon: &Beacon, callback: Option<&Py<PyAny>>) -> Option<PyErr> {
    if let Err(e) = py.check_signals() {
        return Some(e);
    }
    let callback = callback?;
    let newest = beacon
        .newest
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .take()?;
    callback.call1(py, newest).err()
}
