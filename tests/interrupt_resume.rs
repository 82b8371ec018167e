//! Nothing is lost: Ctrl-C or SIGTERM during a render writes the finished tiles as a valid
//! EXR of its own beside the output (`<name>.partial.exr`: unfinished pixels alpha 0,
//! `conetrace.incomplete = 1`, the finished tiles listed) and exits with status 3, leaving
//! the outputs of an earlier complete run as they were; `--resume` refuses a partial render
//! whose scene, referenced files or options changed, renders only the missing tiles and gives
//! the same image, bit for bit, as an uninterrupted run; a failing run never replaces an
//! existing output.
//!
//! The interruption is timing-dependent, so the test adapts instead of asserting times: if
//! the signal came before any tile finished it waits longer, if the render finished first it
//! asks for more samples.

mod common;

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Child, ExitStatus, Stdio};
use std::thread::sleep;
use std::time::Duration;

use common::*;
use conetrace::film::{read_exr, Film, Layer};
use conetrace::render::work_tiles;
use nix::sys::signal::{kill, Signal};
use nix::sys::stat::Mode;
use nix::unistd::{mkfifo, Pid};

/// The header attribute of a partial render that lists its finished work tiles.
const TILES_DONE_ATTRIBUTE: &str = "conetrace.tiles_done";

/// Reads `conetrace.tiles_done` as the binary documents it (src/cli/resume.rs): one
/// hexadecimal digit per four work tiles in row-major order, tile `4k + b` finished when bit
/// `b` of digit `k` is set. `None` when the text does not describe `count` tiles.
fn decode_tiles(text: &str, count: usize) -> Option<Vec<bool>> {
    if text.len() != count.div_ceil(4) {
        return None;
    }
    let digits: Option<Vec<u32>> = text.chars().map(|c| c.to_digit(16)).collect();
    let finished: Vec<bool> = digits?
        .iter()
        .flat_map(|&digit| (0..4).map(move |bit| digit & (1 << bit) != 0))
        .collect();
    // Bits past the last tile must be clear.
    if finished[count..].iter().any(|&done| done) {
        return None;
    }
    Some(finished[..count].to_vec())
}

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

/// `x.exr` -> `x.partial.exr`: where an interrupted render's finished part goes.
fn partial(out: &str) -> String {
    out.replace(".exr", ".partial.exr")
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

/// Polls `child` until it exits and returns how long that took; after `limit` it is killed
/// and the test fails, saying the process was `what` (a signal it did not answer).
fn wait_for_exit(child: &mut Child, limit: Duration, what: &str) -> Duration {
    let step = Duration::from_millis(20);
    let mut waited = Duration::ZERO;
    while child.try_wait().expect("poll conetrace").is_none() {
        if waited > limit {
            child.kill().ok();
            panic!("conetrace {what}: still running {waited:?} after the signal");
        }
        sleep(step);
        waited += step;
    }
    waited
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
    interrupted_render_with(dir, out, signal_name, &[], || {})
}

/// [`interrupted_render`] with `extra` arguments (e.g. a scene) placed after `render`;
/// `restore` runs after a render that finished before the signal, to put back the files an
/// attempt expects to find.
fn interrupted_render_with(
    dir: &Path,
    out: &str,
    signal_name: Signal,
    extra: &[String],
    restore: impl Fn(),
) -> u32 {
    let mut spp = 4;
    let mut delay_ms = 400;
    for _attempt in 0..8 {
        let mut args = render_args(spp, out);
        for (i, arg) in extra.iter().enumerate() {
            args.insert(1 + i, arg.clone());
        }
        let child = start(dir, &args);
        sleep(Duration::from_millis(delay_ms));
        signal(&child, signal_name);
        let (status, stderr) = finish(child);
        match status.code() {
            Some(3) if stderr.contains("nothing written") => {
                assert!(
                    !dir.join(partial(out)).exists(),
                    "nothing finished, yet {} exists",
                    partial(out)
                );
                delay_ms *= 2;
            }
            Some(3) => {
                assert_eq!(stderr.lines().count(), 1, "{stderr}");
                assert!(stderr.contains("--resume"), "{stderr}");
                return spp;
            }
            // Killed by the signal itself before the program reached `main` (only exec and
            // dynamic loading come before the handler): nothing ran, so wait longer. A signal
            // while the scene loads is caught; the FIFO test below pins that down.
            None if status.signal() == Some(signal_name as i32) && stderr.is_empty() => {
                delay_ms *= 2;
            }
            Some(0) => {
                // Finished before the signal: more work next time, fresh output.
                std::fs::remove_file(dir.join(out)).expect("remove finished output");
                restore();
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
    let spp = interrupted_render(dir.path(), "render.exr", Signal::SIGINT);
    assert!(!dir.path().join("render.exr").exists());

    // The partial file is a valid EXR that says it is incomplete.
    let (partial, attributes) =
        read_exr(&dir.path().join("render.partial.exr")).expect("valid EXR");
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
    assert!(!dir.path().join("render.png").exists());

    // A resume with other settings is refused, says which, and leaves the partial file
    // untouched.
    let before = std::fs::read(dir.path().join("render.partial.exr")).unwrap();
    let mut other = render_args(spp + 1, "render.exr");
    other.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &other));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--spp changed") && stderr.contains(&format!("now: {}", spp + 1)),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(dir.path().join("render.partial.exr")).unwrap(),
        before
    );
    // So is one without the surface AOVs the partial file has.
    let mut bare = render_args(spp, "render.exr");
    bare.extend(["--aov", "none", "--resume"].map(String::from));
    let (status, stderr) = finish(start(dir.path(), &bare));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("aov-surface changed"), "{stderr}");
    assert_eq!(
        std::fs::read(dir.path().join("render.partial.exr")).unwrap(),
        before
    );

    // --resume finishes it into the output and removes the partial file.
    let mut resume = render_args(spp, "render.exr");
    resume.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &resume));
    assert!(status.success(), "resume failed: {stderr}");
    let (resumed, attributes) = read_exr(&dir.path().join("render.exr")).unwrap();
    assert!(!dir.path().join("render.partial.exr").exists());
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

/// An interrupted `--region` render (edges off the tile grid) resumes as a whole one does:
/// the partial file holds the region, `--resume` with another region is refused, and the
/// resumed EXR equals an uninterrupted render of the region, bit for bit.
#[test]
fn an_interrupted_region_render_resumes_to_the_uninterrupted_region() {
    let dir = temp_dir();
    let region = ["--region", "10,6,90,60"].map(String::from);
    let spp = interrupted_render_with(dir.path(), "region.exr", Signal::SIGINT, &region, || {});
    let (partial, attributes) =
        read_exr(&dir.path().join("region.partial.exr")).expect("valid EXR");
    assert!(attributes.incomplete);
    let window = attributes
        .window
        .expect("the partial region has a data window");
    assert_eq!(
        (window.x0, window.y0, partial.width(), partial.height()),
        (10, 6, 80, 54)
    );

    let before = std::fs::read(dir.path().join("region.partial.exr")).unwrap();
    let mut other = render_args(spp, "region.exr");
    other.extend(["--region", "0,6,90,60", "--resume"].map(String::from));
    let (status, stderr) = finish(start(dir.path(), &other));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("region 10,6,90,60"), "{stderr}");
    assert_eq!(
        std::fs::read(dir.path().join("region.partial.exr")).unwrap(),
        before
    );

    let mut resume = render_args(spp, "region.exr");
    resume.extend(region.iter().cloned().chain(["--resume".to_string()]));
    let (status, stderr) = finish(start(dir.path(), &resume));
    assert!(status.success(), "resume failed: {stderr}");
    assert!(!dir.path().join("region.partial.exr").exists());
    let (resumed, attributes) = read_exr(&dir.path().join("region.exr")).unwrap();
    assert!(!attributes.incomplete);
    assert_eq!(attributes.window, Some(window));

    let mut uninterrupted = render_args(spp, "full.exr");
    uninterrupted.extend(region.iter().cloned());
    let (status, stderr) = finish(start(dir.path(), &uninterrupted));
    assert!(status.success(), "{stderr}");
    let (full, _) = read_exr(&dir.path().join("full.exr")).unwrap();
    assert_films_identical(&resumed, &full);
}

#[test]
fn sigterm_also_interrupts_with_status_3() {
    let dir = temp_dir();
    interrupted_render(dir.path(), "t.exr", Signal::SIGTERM);
    let (_, attributes) = read_exr(&dir.path().join("t.partial.exr")).expect("valid EXR");
    assert!(attributes.incomplete);
    assert!(attributes.strings.contains_key(TILES_DONE_ATTRIBUTE));
}

/// A signal while the scene is still being read ends the render at once: status 3, one line
/// saying nothing was written, and no file. The scene is a FIFO the test opens for writing
/// and never writes to, so conetrace sits inside scene loading, waiting for text that does
/// not come; it must not wait for it. Both the one-shot and the progressive (`--time-limit`)
/// render are checked. SIGTERM here used to kill the process by the default action (the
/// handler was installed after loading), and then, caught, to wait for the text forever.
#[test]
fn a_signal_while_the_scene_loads_ends_the_render_at_once_writing_nothing() {
    for (signal_name, extra) in [
        (Signal::SIGTERM, &[][..]),
        (Signal::SIGINT, &["--time-limit", "60"][..]),
    ] {
        let dir = temp_dir();
        let fifo = dir.path().join("scene.toml");
        mkfifo(&fifo, Mode::S_IRUSR | Mode::S_IWUSR).expect("mkfifo");
        let mut args = render_args(1, "early.exr");
        args.insert(1, "scene.toml".into());
        args.extend(extra.iter().map(|s| s.to_string()));
        let mut child = start(dir.path(), &args);
        // Opening a FIFO for writing returns once a reader has opened it: conetrace is then
        // inside scene loading, blocked reading.
        let writer = std::fs::OpenOptions::new()
            .write(true)
            .open(&fifo)
            .expect("open the FIFO for writing");
        signal(&child, signal_name);
        let what = format!("still loading after {signal_name} ({extra:?})");
        wait_for_exit(&mut child, Duration::from_secs(60), &what);
        drop(writer);
        let (status, stderr) = finish(child);
        assert_eq!(
            status.code(),
            Some(3),
            "{signal_name} {extra:?}: {status}, {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains("nothing written"), "{stderr}");
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["scene.toml"], "{signal_name} {extra:?}");
    }
}

#[test]
fn resume_without_an_earlier_file_is_bad_input() {
    let dir = temp_dir();
    let mut args = render_args(1, "absent.exr");
    args.push("--resume".into());
    let (status, stderr) = finish(start(dir.path(), &args));
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("absent.partial.exr"), "{stderr}");
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

#[test]
fn an_interrupted_render_leaves_the_finished_outputs_of_an_earlier_run_alone() {
    let dir = temp_dir();
    let finished = |spp: u32| {
        let mut args = render_args(spp, "keep.exr");
        args.retain(|a| a != "--no-png");
        let (status, stderr) = finish(start(dir.path(), &args));
        assert!(status.success(), "{stderr}");
    };
    finished(1);
    let exr = std::fs::read(dir.path().join("keep.exr")).unwrap();
    let png = std::fs::read(dir.path().join("keep.png")).unwrap();
    let restore = || {
        std::fs::write(dir.path().join("keep.exr"), &exr).unwrap();
        std::fs::write(dir.path().join("keep.png"), &png).unwrap();
    };
    interrupted_render_with(dir.path(), "keep.exr", Signal::SIGINT, &[], restore);
    assert!(
        std::fs::read(dir.path().join("keep.exr")).unwrap() == exr,
        "the interrupted run replaced the finished keep.exr"
    );
    assert!(
        std::fs::read(dir.path().join("keep.png")).unwrap() == png,
        "the interrupted run replaced the finished keep.png"
    );
    let (_, attributes) = read_exr(&dir.path().join("keep.partial.exr")).expect("partial EXR");
    assert!(attributes.incomplete);
}

/// The default scene as a TOML file in `dir/scenes/`, its models and textures reached through
/// links to the repository's assets, so the test can edit it.
fn editable_default_scene(dir: &Path) -> std::path::PathBuf {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    for sub in ["models", "textures"] {
        std::os::unix::fs::symlink(assets.join(sub), dir.join(sub)).unwrap();
    }
    let scene = dir.join("scenes/default.toml");
    std::fs::copy(assets.join("scenes/default.toml"), &scene).expect("assets/scenes/default.toml");
    scene
}

#[test]
fn resume_names_what_changed_and_accepts_the_same_scene_by_another_path() {
    let dir = temp_dir();
    let scene = editable_default_scene(dir.path());
    let original = std::fs::read_to_string(&scene).unwrap();
    let relative = vec!["scenes/default.toml".to_string()];
    let spp = interrupted_render_with(dir.path(), "s.exr", Signal::SIGINT, &relative, || {});
    let resume_with = |scene_arg: &str| {
        let mut args = render_args(spp, "s.exr");
        args.insert(1, scene_arg.to_string());
        args.push("--resume".into());
        finish(start(dir.path(), &args))
    };

    // A brighter light: one image would show two scenes, so it is refused.
    let intensity = original
        .lines()
        .find(|l| l.trim_start().starts_with("intensity"))
        .expect("the default scene's light has an intensity")
        .to_string();
    let brighter = original.replacen(&intensity, "intensity = 123.0", 1);
    assert_ne!(brighter, original);
    std::fs::write(&scene, &brighter).unwrap();
    let (status, stderr) = resume_with("scenes/default.toml");
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("lights changed"), "{stderr}");

    // A changed texture file is refused too, and named.
    std::fs::write(&scene, &original).unwrap();
    let checker = dir.path().join("textures_copy");
    std::fs::remove_file(dir.path().join("textures")).unwrap();
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures");
    std::fs::create_dir(&checker).unwrap();
    for entry in std::fs::read_dir(&assets).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), checker.join(entry.file_name())).unwrap();
    }
    std::fs::rename(&checker, dir.path().join("textures")).unwrap();
    let texture_file = std::fs::read_dir(dir.path().join("textures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| original.contains(&*p.file_name().unwrap().to_string_lossy()))
        .expect("the default scene names one of assets/textures");
    let mut bytes = std::fs::read(&texture_file).unwrap();
    bytes.extend_from_slice(b"trailing bytes change the file");
    std::fs::write(&texture_file, &bytes).unwrap();
    let (status, stderr) = resume_with("scenes/default.toml");
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("texture") && stderr.contains("changed"),
        "{stderr}"
    );
    std::fs::copy(
        assets.join(texture_file.file_name().unwrap()),
        &texture_file,
    )
    .unwrap();

    // The unchanged scene given by its absolute path is the same scene.
    let (status, stderr) = resume_with(scene.to_str().unwrap());
    assert!(status.success(), "{stderr}");
    assert!(dir.path().join("s.exr").exists());
}

/// Ctrl-C stops a render within a run of samples, not at the end of a work tile: one
/// 16x16 tile of 100 million samples per pixel (hours of work) stops promptly with status
/// 3, writes nothing, and says so. Before the fix the tile ran on and the signal was
/// ignored until it finished.
#[test]
fn sigint_stops_a_tile_with_many_samples_mid_way() {
    let dir = temp_dir();
    let args: Vec<String> = [
        "render",
        "-o",
        "slow.exr",
        "--no-png",
        "--quiet",
        "--threads",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "100000000",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut delay_ms = 500;
    for _attempt in 0..5 {
        let mut child = start(dir.path(), &args);
        sleep(Duration::from_millis(delay_ms));
        signal(&child, Signal::SIGINT);
        // A generous bound that only a render ignoring the signal reaches.
        let waited = wait_for_exit(&mut child, Duration::from_secs(120), "ignored SIGINT");
        let (status, stderr) = finish(child);
        match status.code() {
            // The signal landed before the handler was installed: try later.
            None => delay_ms *= 2,
            Some(3) => {
                assert!(stderr.contains("nothing written"), "{stderr}");
                assert!(!dir.path().join("slow.exr").exists());
                assert!(!dir.path().join("slow.partial.exr").exists());
                eprintln!("stopped {waited:?} after the signal");
                return;
            }
            other => panic!("status {other:?}: {stderr}"),
        }
    }
    panic!("the signal never reached a running render");
}

/// A render interrupted with `--stats` and resumed without it removes the earlier run's
/// `<stats>.partial.json` when it completes (it used to be left behind), and its summary line
/// says how many tiles came from the partial file.
#[test]
fn resume_without_stats_removes_the_partial_statistics_and_says_it_resumed() {
    let dir = temp_dir();
    let stats = ["--stats".to_string(), "stats.json".to_string()];
    // An attempt that finished before the signal wrote stats.json: not this test's.
    let forget_finished = || {
        let _ = std::fs::remove_file(dir.path().join("stats.json"));
    };
    let spp = interrupted_render_with(
        dir.path(),
        "render.exr",
        Signal::SIGINT,
        &stats,
        forget_finished,
    );
    let partial_stats = dir.path().join("stats.partial.json");
    assert!(
        partial_stats.exists(),
        "the interrupted run wrote no partial statistics"
    );
    let (_, attributes) = read_exr(&dir.path().join("render.partial.exr")).expect("valid EXR");
    let tiles = work_tiles(WIDTH, HEIGHT).len();
    let done = decode_tiles(&attributes.strings[TILES_DONE_ATTRIBUTE], tiles)
        .expect("tiles_done attribute decodes")
        .iter()
        .filter(|&&d| d)
        .count();

    let mut resume = render_args(spp, "render.exr");
    resume.push("--resume".into());
    let out = run_in(
        dir.path(),
        &resume.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(&format!(
            "resumed: {done} of {tiles} tiles from render.partial.exr"
        )),
        "{stdout}"
    );
    assert!(dir.path().join("render.exr").exists());
    assert!(!dir.path().join("render.partial.exr").exists());
    assert!(
        !partial_stats.exists(),
        "{} was left behind",
        partial_stats.display()
    );
    assert!(
        !dir.path().join("stats.json").exists(),
        "no --stats this time"
    );
}
