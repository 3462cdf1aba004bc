//! `toothfuse`: the command-line tool. Subcommands: `demo`, `info`, `register`, `fuse`, `eval`,
//! `render`. Errors print one line and exit non-zero; never a panic backtrace.

mod demo;
mod eval;
mod fuse;
mod info;
mod input;
mod register;
mod render;
mod render_cmd;
mod render_fused;
mod render_split;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Fuse intraoral-scan crowns with CBCT roots into one watertight mesh per tooth.
#[derive(Parser)]
#[command(name = "toothfuse", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Most threads to use in all (0: as many as the CPUs allow, at most 4 per step; 1: one
    /// thread). The outputs are the same bit for bit whatever N.
    #[arg(long, global = true, value_name = "N", default_value_t = 0)]
    threads: usize,
    /// Print the progress of the registration, the crown cut and the stitching to stderr, one
    /// line per step ("toothfuse: stitch 5/14"). The outputs are the same with or without it.
    #[arg(long, global = true)]
    progress: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Write a synthetic jaw (IOS jaw mesh, CBCT teeth, ground truth) to a folder.
    Demo(demo::DemoArgs),
    /// Print vertices, faces, labels, boundary loops and closed/manifold facts of a mesh file.
    Info(info::InfoArgs),
    /// Register CBCT teeth to IOS crowns; write the report JSON (synthetic jaw without inputs).
    Register(register::RegisterArgs),
    /// Register, cut and stitch: fused.ply, tooth_<fdi>.ply and report.json into a folder.
    Fuse(fuse::FuseArgs),
    /// Registration ablation and fusion accuracy over synthetic jaws, as Markdown.
    Eval(eval::EvalArgs),
    /// Render a picture of the synthetic jaw (IOS crowns over CBCT teeth) to a PNG.
    Render(render_cmd::RenderArgs),
}

/// The `--progress` callback: one line on stderr per new report (repeats skipped).
fn progress_printer() -> impl FnMut(toothfuse::progress::Progress) -> std::ops::ControlFlow<()> {
    let mut last = None;
    move |p| {
        if last != Some(p) {
            eprintln!("toothfuse: {} {}/{}", p.stage.name(), p.done, p.total);
            last = Some(p);
        }
        std::ops::ControlFlow::Continue(())
    }
}

fn main() -> ExitCode {
    // Output piped into `head` must end quietly, as for any Unix tool, not with a panic.
    #[cfg(unix)]
    // SAFETY: restoring the default SIGPIPE disposition at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Two malloc arenas for the process instead of glibc's default of eight per core: each
    // worker thread's arena keeps mapped the large short-lived buffers it freed (band sampling,
    // crown copies). `toothfuse fuse`, maximum RSS and wall time over 4 runs: a foreign jaw
    // 152-161 MB -> 132-136 MB, a rough phantom jaw 91-94 MB -> 80-83 MB, the same times (one
    // arena: 114-118 MB and 69-71 MB, but ~3 % slower on the rough jaw). The library leaves its
    // host's allocator as it is; a `MALLOC_ARENA_MAX` set in the environment is left to glibc.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        // SAFETY: a glibc tuning call at start-up, before any thread exists; it changes no
        // memory already allocated.
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, 2);
        }
    }
    let cli = Cli::parse();
    let run = || {
        toothfuse::with_max_threads(cli.threads, || match &cli.command {
            Command::Demo(a) => demo::run(a),
            Command::Info(a) => info::run(a),
            Command::Register(a) => register::run(a),
            Command::Fuse(a) => fuse::run(a),
            Command::Eval(a) => eval::run(a),
            Command::Render(a) => render_cmd::run(a),
        })
    };
    let result = if cli.progress {
        toothfuse::progress::with_progress(progress_printer(), run)
    } else {
        run()
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            // One line, whatever the underlying parsers put in their messages.
            let line = chain
                .join(": ")
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            eprintln!("toothfuse: error: {line}");
            ExitCode::FAILURE
        }
    }
}
