//! A render's progress on stderr. On a terminal, a bar redrawn in place. Anywhere else (a
//! farm's log file, a pipe), where a bar shows nothing, a plain line every
//! [`DEFAULT_INTERVAL_SECONDS`] (`CONETRACE_PROGRESS_INTERVAL` seconds when set) and a last
//! one at the end: the fraction of tiles done, the rate and the time left, e.g.
//! `progress: 37% (120/324 tiles), 12.3 tiles/s, ETA 16 s`. A render shorter than one
//! interval prints none.

use std::io::IsTerminal;
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use crate::cli::CommandError;

/// Seconds between two plain progress lines, unless the environment says otherwise.
pub const DEFAULT_INTERVAL_SECONDS: f64 = 10.0;

/// The environment variable that sets the seconds between plain progress lines.
pub const INTERVAL_VARIABLE: &str = "CONETRACE_PROGRESS_INTERVAL";

/// The interval between plain progress lines: [`INTERVAL_VARIABLE`] when set (a number of
/// seconds above 0), else [`DEFAULT_INTERVAL_SECONDS`].
pub fn plain_interval() -> Result<Duration, CommandError> {
    let Some(text) = std::env::var_os(INTERVAL_VARIABLE) else {
        return Ok(Duration::from_secs_f64(DEFAULT_INTERVAL_SECONDS));
    };
    let text = text.to_string_lossy();
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| s.is_finite() && *s > 0.0 && *s < 1e9)
        .map(Duration::from_secs_f64)
        .ok_or_else(|| {
            CommandError::bad_input(format!(
                "{INTERVAL_VARIABLE}={text}: not a finite number of seconds above 0 (and below 1e9)"
            ))
        })
}

/// The progress display of one render of `total` tiles, `already` of them finished by an
/// earlier run (`--resume`).
pub struct RenderProgress {
    bar: indicatif::ProgressBar,
    plain: Option<PlainProgress>,
    already: usize,
}

/// Plain lines: when the next is due, and whether one was printed.
struct PlainProgress {
    started: Instant,
    interval: Duration,
    total: usize,
    state: Mutex<PlainState>,
}

struct PlainState {
    next_line: Instant,
    printed: bool,
    done: usize,
}

impl RenderProgress {
    /// Nothing shown when `quiet`; a bar on a terminal; plain lines every `interval`
    /// elsewhere.
    pub fn new(quiet: bool, total: usize, already: usize, interval: Duration) -> RenderProgress {
        let hidden = RenderProgress {
            bar: indicatif::ProgressBar::hidden(),
            plain: None,
            already,
        };
        if quiet {
            return hidden;
        }
        if !std::io::stderr().is_terminal() {
            let started = Instant::now();
            return RenderProgress {
                plain: Some(PlainProgress {
                    started,
                    interval,
                    total,
                    state: Mutex::new(PlainState {
                        next_line: started + interval,
                        printed: false,
                        done: already,
                    }),
                }),
                ..hidden
            };
        }
        let bar = indicatif::ProgressBar::new(total as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {pos}/{len} tiles, {per_sec}, ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_position(already as u64);
        RenderProgress { bar, ..hidden }
    }

    /// `done` tiles of this run finished (the render's progress hook; any thread).
    pub fn update(&self, done: usize) {
        let done = self.already + done;
        self.bar.set_position(done as u64);
        let Some(plain) = &self.plain else {
            return;
        };
        let now = Instant::now();
        let mut state = plain.state.lock().unwrap_or_else(PoisonError::into_inner);
        state.done = state.done.max(done);
        if now >= state.next_line {
            state.next_line = now + plain.interval;
            state.printed = true;
            eprintln!("{}", plain.line(state.done, self.already, now, false));
        }
    }

    /// The render ended: the bar goes; after plain lines, a last one.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
        let Some(plain) = &self.plain else {
            return;
        };
        let state = plain.state.lock().unwrap_or_else(PoisonError::into_inner);
        if state.printed {
            eprintln!(
                "{}",
                plain.line(state.done, self.already, Instant::now(), true)
            );
        }
    }
}

impl PlainProgress {
    /// `progress: 37% (120/324 tiles), 12.3 tiles/s, ETA 16 s`; at the end the elapsed time
    /// instead of the ETA.
    fn line(&self, done: usize, already: usize, now: Instant, last: bool) -> String {
        let seconds = now.duration_since(self.started).as_secs_f64();
        let rate = (done - already) as f64 / seconds.max(1e-9);
        let percent = 100 * done / self.total.max(1);
        let mut line = format!(
            "progress: {percent}% ({done}/{} tiles), {rate:.1} tiles/s",
            self.total
        );
        if last {
            line.push_str(&format!(", {seconds:.1} s"));
        } else if rate > 0.0 {
            let left = (self.total - done) as f64 / rate;
            line.push_str(&format!(", ETA {left:.0} s"));
        } else {
            line.push_str(", ETA unknown");
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain(total: usize) -> PlainProgress {
        let started = Instant::now();
        PlainProgress {
            started,
            interval: Duration::from_secs(10),
            total,
            state: Mutex::new(PlainState {
                next_line: started,
                printed: false,
                done: 0,
            }),
        }
    }

    #[test]
    fn a_line_gives_the_fraction_the_rate_and_the_time_left() {
        let progress = plain(324);
        let later = progress.started + Duration::from_secs(10);
        assert_eq!(
            progress.line(120, 0, later, false),
            "progress: 37% (120/324 tiles), 12.0 tiles/s, ETA 17 s"
        );
        // Tiles an earlier run finished count as done but not towards the rate.
        assert_eq!(
            progress.line(220, 100, later, false),
            "progress: 67% (220/324 tiles), 12.0 tiles/s, ETA 9 s"
        );
        assert_eq!(
            progress.line(324, 0, later, true),
            "progress: 100% (324/324 tiles), 32.4 tiles/s, 10.0 s"
        );
        assert_eq!(
            progress.line(0, 0, later, false),
            "progress: 0% (0/324 tiles), 0.0 tiles/s, ETA unknown"
        );
    }
}
