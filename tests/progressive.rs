//! `conetrace render --time-limit SECONDS` renders passes of samples until the time is spent
//! and rewrites its outputs after each pass (src/cli/progressive.rs): every file a reader
//! finds meanwhile is a complete EXR; the image equals a single render of the same samples
//! bit for bit; Ctrl-C keeps the last complete pass and exits with status 3.
//!
//! Times are not asserted: the tests only rely on a pass finishing eventually.

mod common;

use std::path::Path;
use std::process::{Child, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

use common::*;
use conetrace::film::{read_exr, Film, Layer};
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

const SIZE: [&str; 4] = ["--width", "96", "--height", "64"];

fn args<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", "-o", out, "--quiet", "--threads", "2"];
    args.extend(SIZE);
    args.extend(extra);
    args
}

fn start(dir: &Path, args: &[&str]) -> Child {
    conetrace()
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start conetrace")
}

/// The samples per pixel an output holds, from its header.
fn samples_of(path: &Path) -> (Film, u32) {
    let (film, attributes) =
        read_exr(path).unwrap_or_else(|e| panic!("{} is not a complete EXR: {e}", path.display()));
    let samples = attributes
        .strings
        .get("conetrace.progressive.samples")
        .unwrap_or_else(|| panic!("no conetrace.progressive.samples in {}", path.display()))
        .parse()
        .expect("a sample count");
    assert_eq!(
        attributes.strings["conetrace.samples"],
        format!("0..{samples}")
    );
    (film, samples)
}

/// Bit-compares every channel the two films share except the exact sums, which only a
/// sample-range render keeps.
fn assert_same_pixels(a: &Film, b: &Film) {
    let names: Vec<String> = a
        .channel_names()
        .into_iter()
        .filter(|n| !n.starts_with("sum."))
        .collect();
    let b_names: Vec<String> = b
        .channel_names()
        .into_iter()
        .filter(|n| !n.starts_with("sum."))
        .collect();
    assert_eq!(names, b_names);
    for name in names {
        let (pa, pb) = (a.channel(&name).unwrap(), b.channel(&name).unwrap());
        let differing = pa
            .iter()
            .zip(pb)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(differing, 0, "channel {name}: {differing} pixels differ");
    }
}

/// The first `samples` samples of the unbounded render (whose sample count is u32::MAX),
/// rendered at once as a sample range.
fn one_shot_of_unbounded(dir: &Path, samples: u32) -> Film {
    let range = format!("0..{samples}");
    let out = run_in(
        dir,
        &args(
            "oneshot.exr",
            &["--spp", "4294967295", "--samples", &range, "--no-png"],
        ),
    );
    assert!(out.status.success(), "{out:?}");
    read_exr(&dir.join("oneshot.exr")).expect("one-shot EXR").0
}

#[test]
fn a_time_limited_render_rewrites_complete_images_while_it_converges() {
    let dir = temp_dir();
    let exr = dir.path().join("p.exr");
    let child = start(
        dir.path(),
        &args("p.exr", &["--time-limit", "2", "--stats", "p.json"]),
    );
    let mut seen = Vec::new();
    let polling = Instant::now();
    let mut child = child;
    let status = loop {
        if exr.exists() {
            // Renamed into place whole: a reader never finds a partial file.
            let (film, samples) = samples_of(&exr);
            assert!(film.channel("A").unwrap().iter().all(|&a| a == 1.0));
            if seen.last() != Some(&samples) {
                seen.push(samples);
            }
        }
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(polling.elapsed() < Duration::from_secs(300), "never ended");
        sleep(Duration::from_millis(10));
    };
    let output = child.wait_with_output().expect("output");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(status.success(), "{status} {output:?}");
    let (_, final_samples) = samples_of(&exr);
    assert!(final_samples >= 1);
    assert!(
        seen.windows(2).all(|w| w[0] < w[1]),
        "sample counts seen: {seen:?}"
    );
    assert!(dir.path().join("p.png").exists());
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("p.json")).unwrap()).unwrap();
    let progressive = &stats["progressive"];
    assert_eq!(progressive["samples"], final_samples);
    assert_eq!(stats["spp"], final_samples);
    assert_eq!(progressive["stopped_by"], "time");
    let passes = progressive["passes"].as_u64().unwrap();
    assert!(passes >= 1);
    let pass_words = if passes == 1 {
        "1 pass".to_string()
    } else {
        format!("{passes} passes")
    };
    assert!(
        stdout.contains(&format!(
            "progressive: {pass_words}, {final_samples} spp reached"
        )),
        "{stdout}"
    );
    // No temporary file is left behind.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");

    // The image is that of its samples rendered at once.
    let (film, _) = samples_of(&exr);
    assert_same_pixels(&film, &one_shot_of_unbounded(dir.path(), final_samples));
}

#[test]
fn a_progressive_render_that_reaches_spp_equals_the_one_shot_render() {
    let dir = temp_dir();
    // The time limit is far away: the render stops at the 8 samples of --spp.
    let out = run_in(
        dir.path(),
        &args("p.exr", &["--spp", "8", "--time-limit", "600"]),
    );
    assert!(out.status.success(), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("4 passes, 8 spp reached, stopped by samples"),
        "{out:?}"
    );
    let out = run_in(dir.path(), &args("one.exr", &["--spp", "8"]));
    assert!(out.status.success(), "{out:?}");
    let (progressive, samples) = samples_of(&dir.path().join("p.exr"));
    assert_eq!(samples, 8);
    let (one_shot, _) = read_exr(&dir.path().join("one.exr")).unwrap();
    assert_same_pixels(&progressive, &one_shot);
    assert_eq!(
        std::fs::read(dir.path().join("p.png")).unwrap(),
        std::fs::read(dir.path().join("one.png")).unwrap()
    );
}

/// Without --quiet, each completed pass is one plain line on stderr, so a farm's log shows
/// how far a progressive render has come (it printed nothing before).
#[test]
fn each_completed_pass_prints_a_plain_progress_line() {
    let dir = temp_dir();
    let out = run_in(
        dir.path(),
        &[
            "render",
            "-o",
            "p.exr",
            "--threads",
            "2",
            "--spp",
            "4",
            "--time-limit",
            "600",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("progress: pass"))
        .collect();
    // Passes of 1, 1 and 2 samples reach 4.
    assert_eq!(lines.len(), 3, "{stderr}");
    for (line, (pass, spp)) in lines.iter().zip([(1, 1), (2, 2), (3, 4)]) {
        assert!(
            line.starts_with(&format!("progress: pass {pass} done, {spp} spp, "))
                && line.contains(" s of 600 s; wrote p.exr"),
            "{line}"
        );
    }
}

#[test]
fn a_progressive_render_of_one_pass_says_one_pass() {
    let dir = temp_dir();
    // One sample is one pass: the render stops at --spp after it.
    let out = run_in(
        dir.path(),
        &args("p.exr", &["--spp", "1", "--time-limit", "600"]),
    );
    assert!(out.status.success(), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("progressive: 1 pass, 1 spp reached, stopped by samples"),
        "{stdout}"
    );
}

#[test]
fn ctrl_c_keeps_the_last_complete_pass_and_exits_with_status_3() {
    let dir = temp_dir();
    let exr = dir.path().join("p.exr");
    let child = start(dir.path(), &args("p.exr", &["--time-limit", "600"]));
    // Wait for a few passes, then interrupt the render in flight.
    let waiting = Instant::now();
    loop {
        if exr.exists() && samples_of(&exr).1 >= 4 {
            break;
        }
        assert!(
            waiting.elapsed() < Duration::from_secs(300),
            "no 4-sample pass in 300 s"
        );
        sleep(Duration::from_millis(10));
    }
    let pid = Pid::from_raw(i32::try_from(child.id()).unwrap());
    kill(pid, Signal::SIGINT).expect("send SIGINT");
    let output = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(3), "{stderr}");
    let (film, samples) = samples_of(&exr);
    assert!(samples >= 4);
    assert!(
        stderr.contains(&format!("({samples} samples per pixel)")),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains(&format!(
            "{samples} spp reached, stopped by an interrupt (time limit 600 s)"
        )),
        "{stdout}"
    );
    assert!(film.has(Layer::Depth));
    assert_same_pixels(&film, &one_shot_of_unbounded(dir.path(), samples));
}

#[test]
fn bad_time_limits_are_refused_before_anything_is_written() {
    let dir = temp_dir();
    for extra in [
        vec!["--time-limit", "0"],
        vec!["--time-limit", "-3"],
        vec!["--time-limit", "2", "--resume"],
        vec!["--time-limit", "2", "--samples", "0..1"],
    ] {
        let out = run_in(dir.path(), &args("p.exr", &extra));
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {out:?}");
        assert!(!dir.path().join("p.exr").exists(), "{extra:?}");
    }
}

/// User plus system CPU time of process `pid`, in clock ticks (fields 14 and 15 of
/// /proc/PID/stat, counted after the parenthesised command name).
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("read /proc stat");
    let fields: Vec<&str> = stat[stat.rfind(')').expect("stat line") + 2..]
        .split(' ')
        .collect();
    fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap()
}

#[test]
fn a_pass_the_deadline_overtakes_is_reported_as_left_out() {
    // The process is stopped (SIGSTOP) once its first pass is on disk, in the second pass,
    // and continued (SIGCONT) after the deadline: as on a machine whose other work
    // took the time the pass was planned with. The second pass is left out, and the summary
    // line and the statistics say so.
    let dir = temp_dir();
    let exr = dir.path().join("p.exr");
    let started = Instant::now();
    let child = start(
        dir.path(),
        &[
            "render",
            "-o",
            "p.exr",
            "--quiet",
            "--no-png",
            "--threads",
            "1",
            "--width",
            "512",
            "--height",
            "512",
            "--time-limit",
            "10",
            "--stats",
            "p.json",
        ],
    );
    let pid = Pid::from_raw(i32::try_from(child.id()).unwrap());
    while !exr.exists() {
        assert!(
            started.elapsed() < Duration::from_secs(9),
            "the first pass took more than 9 of the 10 seconds"
        );
        sleep(Duration::from_millis(2));
    }
    // The outputs are renamed into place before the backups are removed and the directory
    // synced, which can wait on the disk; the pass that follows is the first CPU time spent
    // after them (a tenth of a second at least).
    let first_pass = started.elapsed();
    let cpu_at_write = cpu_ticks(child.id());
    while cpu_ticks(child.id()) < cpu_at_write + 5 {
        assert!(
            started.elapsed() < Duration::from_secs(9),
            "no second pass within 9 of the 10 seconds (first pass on disk after {:?})",
            first_pass
        );
        sleep(Duration::from_millis(2));
    }
    kill(pid, Signal::SIGSTOP).expect("send SIGSTOP");
    let (_, samples_before) = samples_of(&exr);
    sleep(Duration::from_secs(11).saturating_sub(started.elapsed()));
    kill(pid, Signal::SIGCONT).expect("send SIGCONT");
    let output = child.wait_with_output().expect("wait");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{output:?}");
    let (_, samples) = samples_of(&exr);
    assert_eq!(
        samples, samples_before,
        "the outputs changed after the deadline"
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("p.json")).unwrap()).unwrap();
    let progressive = &stats["progressive"];
    assert_eq!(progressive["stopped_by"], "time");
    let abandoned = progressive["abandoned_samples"]
        .as_u64()
        .unwrap_or_else(|| panic!("no abandoned_samples in {progressive}"));
    assert!(abandoned >= 1, "{progressive}");
    assert!(
        stdout.contains(&format!(
            "a pass of {abandoned} spp was overtaken by the deadline and left out"
        )),
        "{stdout}"
    );
}
