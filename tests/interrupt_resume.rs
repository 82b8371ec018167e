//! Nothing is lost (issue 6, part 6): Ctrl-C or SIGTERM during a render writes the finished
//! tiles as a valid EXR (unfinished pixels alpha 0, `conetrace.incomplete = 1`, the finished
//! tiles listed) and exits with status 3; `--resume` renders only the missing tiles and gives
//! the same image, bit for bit, as an uninterrupted run; a failing run never replaces an
//! existing output.
//!
//! The interruption is timing-dependent, so the test adapts instead of asserting times: if
//! the signal came before any tile finished it waits longer, if the render finished first it
//! asks for more samples.

mod common;

use std::path::Path;
use std::process::{Child, ExitStatus, Stdio};
use std::thread::sleep;
use std::time::Duration;

use common::*;
use conetrace::cli::render_cmd::{decode_tiles, TILES_DONE_ATTRIBUTE};
use conetrace::film::{read_exr, Film, Layer};
use conetrace::render::work_tiles;
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

const WIDTH: u32 = 96;
const HEIGHT: u32 = 64;

fn render_args(spp: u32, out: &str) -> Vec<String> {
    [
        "render",
        "-o",
        out,
        "--no-png",
        "--quiet",
        "--threads",
        "2",
        "--width",
        &WIDTH.to_string(),
        "--height",
        &HEIGHT.to_string(),
        "--spp",
        &spp.to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn start(dir: &Path, args: &[String]) -> Child {
    conetrace()
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start conetrace")
}

/// Send `signal` to the child directly (kill(2)), so the test needs no `kill` program.
fn signal(child: &Child, signal: Signal) {
    let pid = Pid::from_raw(i32::try_from(child.id()).expect("a pid fits in i32"));
    kill(pid, signal).unwrap_or_else(|e| panic!("kill({pid}, {signal}) failed: {e}"));
}

fn finish(child: Child) -> (ExitStatus, String) {
    let out = child.wait_with_output().expect("wait for conetrace");
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Start a render and interrupt it with `signal_name`, adapting delay and samples until the
/// interruption lands mid-render. Returns the spp used.
fn interrupted_render(dir: &Path, out: &str, signal_name: Signal) -> u32 {
    let mut spp = 4;
    let mut delay_ms = 400;
    for _attempt in 0..8 {
        let child = start(dir, &render_args(spp, out));
        sleep(Duration::from_millis(delay_ms));
        signal(&child, signal_name);
        let (status, stderr) = finish(child);
        match status.code() {
            Some(3) if stderr.contains("nothing written") => {
                assert!(
                    !dir.join(out).exists(),
                    "nothing finished, yet {out} exists"
                );
                delay_ms *= 2;
            }
            Some(3) => {
                assert_eq!(stderr.lines().count(), 1, "{stderr}");
                assert!(stderr.contains("--resume"), "{stderr}");
                return spp;
            }
            Some(0) => {
                // Finished before the signal: more work next time, fresh output.
                std::fs::remove_file(dir.join(out)).expect("remove finished output");
                spp *= 4;
            }
            other => panic!("interrupted render: status {other:?} ({status}), stderr {stderr}"),
        }
    }
    panic!("could not interrupt a render mid-way in 8 attempts");
}

fn assert_films_identical(a: &Film, b: &Film) {
    assert_eq!(a.channel_names(), b.channel_names());
    for name in a.channel_names() {
        let (pa, pb) = (a.channel(&name).unwrap(), b.channel(&name).unwrap());
        let differing = pa
            .iter()
            .zip(pb)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(differing, 0, "channel {name}: {differing} pixels differ");
    }
}

#[test]
fn sigint_writes_the_finished_part_and_resume_matches_an_uninterrupted_run() {
    let dir = temp_dir();
    let spp = interrupted_render(dir.path(), "partial.exr", Signal::SIGINT);

    // The partial file is a valid EXR that says it is incomplete.
    let (partial, attributes) = read_exr(&dir.path().join("partial.exr")).expect("valid EXR");
    assert!(attributes.incomplete);
    let tiles = work_tiles(WIDTH, HEIGHT);
    let done = decode_tiles(&attributes.strings[TILES_DONE_ATTRIBUTE], tiles.len())
        .expect("tiles_done attribute decodes");
    let done_count = done.iter().filter(|&&d| d).count();
    assert!(done_count > 0 && done_count < tiles.len(), "{done_count}");
    assert_eq!(attributes.finished_tiles, Some(done_count as u32));
    // Unfinished pixels are all zero, alpha included (finished ones are checked against the
    // uninterrupted run below; their alpha is the coverage, 0 where the camera ray missed).
    let mut rgba = [0.0f32; 4];
    for (tile, _) in tiles.iter().zip(&done).filter(|(_, &d)| !d) {
        for (x, y) in tile.pixels() {
            partial.get(Layer::Color, x, y, &mut rgba);
            assert_eq!(rgba, [0.0; 4], "unfinished pixel ({x},{y})");
        }
    }
    assert!(!dir.path().join("partial.png").exists());

    // A resume with other settings is refused and leaves the partial file untouched.
    let before = std::fs::read(dir.path().join("partial.exr")).unwrap();
    let mut other = render_args(spp + 1, "partial.exr");
    other.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &other));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("different settings"), "{stderr}");
    assert_eq!(
        std::fs::read(dir.path().join("partial.exr")).unwrap(),
        before
    );

    // --resume finishes it.
    let mut resume = render_args(spp, "partial.exr");
    resume.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &resume));
    assert!(status.success(), "resume failed: {stderr}");
    let (resumed, attributes) = read_exr(&dir.path().join("partial.exr")).unwrap();
    assert!(!attributes.incomplete);
    assert_eq!(attributes.finished_tiles, Some(tiles.len() as u32));

    // An uninterrupted run gives the same pixels, bit for bit.
    let (status, stderr) = finish(start(dir.path(), &render_args(spp, "full.exr")));
    assert!(status.success(), "{stderr}");
    let (full, _) = read_exr(&dir.path().join("full.exr")).unwrap();
    assert_films_identical(&resumed, &full);
    // The tiles the interrupted run finished were already right.
    let mut expected = Film::new(WIDTH, HEIGHT, &partial.layers());
    for (tile, _) in tiles.iter().zip(&done).filter(|(_, &d)| d) {
        expected.copy_region_from(&full, *tile);
    }
    assert_films_identical(&partial, &expected);
}

#[test]
fn sigterm_also_interrupts_with_status_3() {
    let dir = temp_dir();
    interrupted_render(dir.path(), "t.exr", Signal::SIGTERM);
    let (_, attributes) = read_exr(&dir.path().join("t.exr")).expect("valid EXR");
    assert!(attributes.incomplete);
    assert!(attributes.strings.contains_key(TILES_DONE_ATTRIBUTE));
}

#[test]
fn resume_without_an_earlier_file_is_bad_input() {
    let dir = temp_dir();
    let mut args = render_args(1, "absent.exr");
    args.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &args));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("absent.exr"), "{stderr}");
    assert!(!dir.path().join("absent.exr").exists());
}

#[test]
fn a_failing_run_leaves_an_existing_output_untouched() {
    let dir = temp_dir();
    let old = b"an earlier output that must survive".to_vec();
    std::fs::write(dir.path().join("keep.exr"), &old).unwrap();
    std::fs::write(dir.path().join("keep.png"), &old).unwrap();
    write(
        dir.path(),
        "bad.toml",
        "[[sphere]]\ncenter = [0, 0, 0]\nradius = -1\n",
    );
    let out = run_in(
        dir.path(),
        &["render", "bad.toml", "-o", "keep.exr", "--quiet"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read(dir.path().join("keep.exr")).unwrap(), old);
    assert_eq!(std::fs::read(dir.path().join("keep.png")).unwrap(), old);
}
