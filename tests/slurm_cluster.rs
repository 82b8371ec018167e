//! The Slurm scripts on a real one-node Slurm cluster (Debian's `slurm-wlm` and `munge`,
//! installed by scripts/setup.sh), started for the test in a temporary directory: munged
//! with its own key and socket, slurmctld and slurmd with a slurm.conf for localhost (state,
//! spool and logs in the directory, free ports), all stopped again by a guard, also when the
//! test fails.
//!
//! - `scripts/slurm/submit.sh SCENE 4` renders the shipped scene as a 4-task array job plus a
//!   merge job that waits for it (`--dependency=afterok`); the merged EXR equals a local
//!   render of the same options, as a file.
//! - A task killed while it renders (`scancel`) fails the array job: the merge job never
//!   runs, no merged image and no part file of the killed task appear. Submitting only that
//!   part again (`submit.sh ... --only i`) completes the image, again equal to a local
//!   render.
//!
//! Runs as root (slurmd starts jobs as their user, here root). When Slurm cannot run here,
//! the test fails and says why.

mod common;

use std::fs;
use std::io::Read;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

use common::*;

/// The options every render of this test uses, besides the samples per pixel.
const SIZE: [&str; 6] = ["--width", "80", "--height", "64", "--aov", "all"];

/// A one-node Slurm cluster in a temporary directory; dropping it cancels its jobs and stops
/// its daemons.
struct LocalCluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

fn program(name: &str) -> PathBuf {
    for dir in ["/usr/sbin", "/usr/bin", "/sbin", "/bin"] {
        let path = Path::new(dir).join(name);
        if path.exists() {
            return path;
        }
    }
    panic!("{name} is not installed: Slurm cannot run here (run scripts/setup.sh, which installs Debian's slurm-wlm and munge)");
}

/// Whether this root has cgroup file systems mounted under /sys/fs/cgroup, as a booted
/// machine has (a chroot usually has no /sys at all).
fn cgroups_mounted() -> bool {
    fs::read_to_string("/proc/self/mountinfo").is_ok_and(|mounts| {
        mounts.lines().any(|line| {
            line.split_whitespace()
                .nth(4)
                .is_some_and(|mount_point| mount_point.starts_with("/sys/fs/cgroup"))
        })
    })
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free local port")
}

impl LocalCluster {
    fn start(dir: &Path) -> LocalCluster {
        assert!(
            {
                use std::os::unix::fs::MetadataExt;
                // /proc/self belongs to the process's effective user.
                fs::metadata("/proc/self").map(|m| m.uid()).ok() == Some(0)
            },
            "Slurm cannot run here: the local cluster needs root (slurmd runs the jobs as root)"
        );
        let munge_dir = dir.join("munge");
        for sub in ["munge", "state", "spool", "log"] {
            fs::create_dir_all(dir.join(sub)).unwrap();
        }
        fs::set_permissions(&munge_dir, fs::Permissions::from_mode(0o700)).unwrap();
        let key = munge_dir.join("munge.key");
        let mut bytes = vec![0u8; 1024];
        fs::File::open("/dev/urandom")
            .and_then(|mut f| f.read_exact(&mut bytes))
            .expect("random bytes for the munge key");
        fs::write(&key, &bytes).unwrap();
        fs::set_permissions(&key, fs::Permissions::from_mode(0o400)).unwrap();
        let socket = munge_dir.join("munge.socket");
        let (ctld_port, slurmd_port) = (free_port(), free_port());
        let d = dir.display();
        let conf = dir.join("slurm.conf");
        fs::write(
            &conf,
            format!(
                "ClusterName=conetrace-test
SlurmctldHost=localhost
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={socket}
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=main Nodes=localhost Default=YES MaxTime=INFINITE State=UP
",
                socket = socket.display()
            ),
        )
        .unwrap();
        if !cgroups_mounted() {
            // A root without cgroup file systems (a chroot): slurmd 22.05 always loads a cgroup
            // plugin, and its default, autodetect, fails there. The v1 plugin loads without
            // touching any hierarchy, and with proctrack/pgid and task/none nothing asks it to.
            fs::write(dir.join("cgroup.conf"), "CgroupPlugin=cgroup/v1\n").unwrap();
        }
        let mut cluster = LocalCluster {
            dir: dir.to_path_buf(),
            conf,
            daemons: Vec::new(),
        };
        cluster.spawn(
            "munged",
            Command::new(program("munged")).args([
                "-F".to_string(),
                "-f".to_string(),
                format!("--socket={}", socket.display()),
                format!("--key-file={}", key.display()),
                format!("--log-file={d}/log/munged.log"),
                format!("--pid-file={}/munged.pid", munge_dir.display()),
                format!("--seed-file={}/munged.seed", munge_dir.display()),
            ]),
        );
        cluster.wait_for("munged to create its socket", || socket.exists());
        let conf_arg = cluster.conf.to_str().unwrap().to_string();
        cluster.spawn(
            "slurmctld",
            Command::new(program("slurmctld")).args(["-D", "-f", &conf_arg]),
        );
        cluster.spawn(
            "slurmd",
            Command::new(program("slurmd")).args(["-D", "-N", "localhost", "-f", &conf_arg]),
        );
        let conf = cluster.conf.clone();
        cluster.wait_for("the node to be idle", || {
            let out = Command::new(program("sinfo"))
                .args(["-h", "-o", "%T"])
                .env("SLURM_CONF", &conf)
                .output();
            out.is_ok_and(|out| String::from_utf8_lossy(&out.stdout).trim() == "idle")
        });
        cluster
    }

    fn spawn(&mut self, name: &'static str, command: &mut Command) {
        let log = fs::File::create(self.dir.join(format!("log/{name}.out"))).unwrap();
        let child = command
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .unwrap_or_else(|e| panic!("Slurm cannot run here: cannot start {name}: {e}"));
        self.daemons.push((name, child));
    }

    /// Waits up to a minute for `ready`, failing with the daemons' logs.
    fn wait_for(&mut self, what: &str, mut ready: impl FnMut() -> bool) {
        let start = Instant::now();
        while !ready() {
            let exited = self.daemons.iter_mut().find_map(|(name, child)| {
                child
                    .try_wait()
                    .ok()
                    .flatten()
                    .map(|status| (*name, status))
            });
            if let Some((name, status)) = exited {
                panic!(
                    "Slurm cannot run here: {name} exited ({status}) while waiting for {what}; {}",
                    self.logs()
                );
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "Slurm cannot run here: timed out waiting for {what}; {}",
                self.logs()
            );
            sleep(Duration::from_millis(100));
        }
    }

    /// The tails of the daemons' logs, for failure messages.
    fn logs(&self) -> String {
        let mut text = String::new();
        for name in [
            "munged.out",
            "munged.log",
            "slurmctld.out",
            "slurmctld.log",
            "slurmd.out",
            "slurmd.log",
        ] {
            let content = fs::read_to_string(self.dir.join("log").join(name)).unwrap_or_default();
            let tail: Vec<&str> = content.lines().rev().take(8).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            text.push_str(&format!("[{name}] {} ", tail.join(" | ")));
        }
        text
    }

    /// Runs a Slurm client command against this cluster.
    fn slurm(&self, program_name: &str, args: &[&str]) -> Output {
        Command::new(program(program_name))
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .output()
            .unwrap_or_else(|e| panic!("{program_name}: {e}"))
    }

    /// A job's (or array task's) state, e.g. RUNNING, COMPLETED, CANCELLED.
    fn job_state(&self, job: &str) -> String {
        let out = self.slurm("scontrol", &["show", "job", job]);
        let text = String::from_utf8_lossy(&out.stdout);
        text.split_whitespace()
            .find_map(|w| w.strip_prefix("JobState="))
            .unwrap_or("UNKNOWN")
            .to_string()
    }

    /// Waits until `job` has ended and returns its final state.
    fn wait_until_ended(&self, job: &str) -> String {
        let start = Instant::now();
        loop {
            let state = self.job_state(job);
            if !["PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "UNKNOWN"]
                .contains(&state.as_str())
            {
                return state;
            }
            assert!(
                start.elapsed() < Duration::from_secs(300),
                "job {job} still {state} after 5 minutes; {}",
                self.logs()
            );
            sleep(Duration::from_millis(200));
        }
    }

    /// `submit.sh SCENE 4 [extra...]` from `dir`; returns (render job, merge job).
    fn submit(&self, dir: &Path, outdir: &Path, extra: &[&str]) -> (String, String) {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm/submit.sh");
        let output = Command::new("bash")
            .arg(&script)
            .arg(scene())
            .arg("4")
            .args(extra)
            .current_dir(dir)
            .env("SLURM_CONF", &self.conf)
            .env("CONETRACE", env!("CARGO_BIN_EXE_conetrace"))
            .env("OUTDIR", outdir)
            .output()
            .expect("submit.sh runs");
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            output.status.success(),
            "submit.sh failed: {} {}",
            stdout,
            String::from_utf8_lossy(&output.stderr)
        );
        // "render job <id> (parts <list>), merge job <id>"
        let words: Vec<&str> = stdout.split_whitespace().collect();
        assert!(
            words.len() == 8 && words[0] == "render" && words[6] == "job",
            "unexpected submit.sh output: {stdout}"
        );
        (words[2].to_string(), words[7].to_string())
    }
}

impl Drop for LocalCluster {
    fn drop(&mut self) {
        // Jobs first, so no task outlives the daemons; then the daemons, gently, then not.
        let _ = self.slurm("scancel", &["--user=root"]);
        sleep(Duration::from_millis(500));
        for (_, child) in &mut self.daemons {
            let _ = nix::sys::signal::kill(
                nix::unistd::Pid::from_raw(child.id() as i32),
                nix::sys::signal::Signal::SIGTERM,
            );
        }
        let deadline = Instant::now() + Duration::from_secs(10);
        for (_, child) in &mut self.daemons {
            while Instant::now() < deadline {
                if let Ok(Some(_)) = child.try_wait() {
                    break;
                }
                sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn scene() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    assert!(
        path.exists(),
        "the shipped scene {} is missing",
        path.display()
    );
    path
}

/// A render of the whole image on this machine with `spp`.
fn local_render(dir: &Path, name: &str, spp: &str) -> PathBuf {
    let out = dir.join(name);
    let scene = scene();
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(["--no-png", "--quiet", "--spp", spp]);
    args.extend(SIZE);
    let output = run_in(dir, &args);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    out
}

fn assert_same_file(merged: &Path, local: &Path) {
    assert!(merged.exists(), "{} was not written", merged.display());
    assert_eq!(
        fs::read(merged).unwrap(),
        fs::read(local).unwrap(),
        "{} differs from the local render {}",
        merged.display(),
        local.display()
    );
}

#[test]
fn slurm_array_render_merges_into_the_local_render_and_recovers_a_killed_task() {
    let dir = temp_dir();
    let d = dir.path();
    let cluster = LocalCluster::start(&d.join("cluster"));

    // A clean run.
    let local = local_render(d, "local.exr", "4");
    let outdir = d.join("parts");
    let mut extra = vec!["--spp", "4"];
    extra.extend(SIZE);
    let (render_job, merge_job) = cluster.submit(d, &outdir, &extra);
    let state = cluster.wait_until_ended(&merge_job);
    assert_eq!(
        state,
        "COMPLETED",
        "merge job {merge_job} (after array {render_job}): {}",
        fs::read_dir(&outdir)
            .map(|entries| entries
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join(", "))
            .unwrap_or_default()
    );
    for i in 0..4 {
        assert!(outdir.join(format!("part-{i}-of-4.exr")).exists());
    }
    assert_same_file(&outdir.join("merged.exr"), &local);

    // A run with a task killed while it renders: enough samples that a part takes seconds
    // even on an idle machine. A render stops at its next work tile once signalled, and one
    // whose every tile had started finishes and writes its part: at 512, and once in a full
    // local run at 2048 (a part of 5 tiles, about 4 s of rendering), the signal came after
    // the last tile had started and the part file was written.
    let spp = "4096";
    let outdir = d.join("killed");
    let mut extra = vec!["--spp", spp];
    extra.extend(SIZE);
    let (render_job, merge_job) = cluster.submit(d, &outdir, &extra);
    let start = Instant::now();
    let victim = loop {
        let out = cluster.slurm("squeue", &["-h", "-r", "-j", &render_job, "-o", "%i %T"]);
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        if let Some(line) = text.lines().find(|l| l.ends_with(" RUNNING")) {
            break line.split_whitespace().next().unwrap().to_string();
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no task of {render_job} started: {text}"
        );
        sleep(Duration::from_millis(20));
    };
    let cancelled = cluster.slurm("scancel", &[&victim]);
    assert!(cancelled.status.success(), "scancel {victim}");
    let victim_state = cluster.wait_until_ended(&victim);
    assert_eq!(
        victim_state, "CANCELLED",
        "task {victim} was to be killed while running (it ended {victim_state})"
    );
    let merge_state = cluster.wait_until_ended(&merge_job);
    assert_ne!(
        merge_state, "COMPLETED",
        "the merge ran after a failed task"
    );
    // Let the other tasks finish, then check what is on disk.
    for i in 0..4 {
        let task = format!("{render_job}_{i}");
        cluster.wait_until_ended(&task);
    }
    let index: usize = victim.rsplit('_').next().unwrap().parse().unwrap();
    assert!(
        !outdir.join("merged.exr").exists(),
        "a merged image despite a killed task"
    );
    assert!(
        !outdir.join(format!("part-{index}-of-4.exr")).exists(),
        "the killed task left its part file"
    );

    // Only the killed part again.
    let index_text = index.to_string();
    let mut extra = vec!["--only", index_text.as_str(), "--spp", spp];
    extra.extend(SIZE);
    let (_, merge_job) = cluster.submit(d, &outdir, &extra);
    let state = cluster.wait_until_ended(&merge_job);
    assert_eq!(
        state, "COMPLETED",
        "the merge after resubmitting part {index}"
    );
    let local = local_render(d, "local512.exr", spp);
    assert_same_file(&outdir.join("merged.exr"), &local);
}
