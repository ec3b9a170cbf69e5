//! CPU time of the calling thread: the cost measure of a run on a shared machine, where wall
//! time also counts other people's jobs.

/// CPU seconds the calling thread has run, from `/proc/thread-self/schedstat` (Linux); `None`
/// where that file does not exist.
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// A stopwatch of wall and (where available) thread CPU time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stopwatch {
    wall: std::time::Instant,
    cpu: Option<f64>,
}

impl Stopwatch {
    pub(crate) fn start() -> Self {
        Self {
            wall: std::time::Instant::now(),
            cpu: thread_cpu_seconds(),
        }
    }

    /// `(wall seconds, CPU seconds)` since the start.
    pub(crate) fn read(&self) -> (f64, Option<f64>) {
        let cpu = match (self.cpu, thread_cpu_seconds()) {
            (Some(a), Some(b)) => Some(b - a),
            _ => None,
        };
        (self.wall.elapsed().as_secs_f64(), cpu)
    }
}
