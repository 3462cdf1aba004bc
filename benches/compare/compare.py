"""Side by side, run by benches/compare/run.sh (which builds the binaries and the venv first).

1. ICP on identical point sets: toothfuse's point-to-plane ICP (examples/icp_compare.rs) against
   Open3D's registration_icp (icp_open3d.py), per tooth of the synthetic jaw and the foreign jaws;
   time per iteration (median of interleaved rounds) and TRE of both.
2. Whole fusion of one foreign jaw: `toothfuse fuse` against the paper-style reference
   (paper_reference.py); wall time of each whole process (median of interleaved rounds), TRE
   against the truth, and each tooth's watertightness checked by VTK.

Prints one markdown table and writes it to build/compare/results.md.
"""

import argparse
import datetime
import importlib.metadata
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import vtk

from plyio import read_ply, split_by_label

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = ROOT / "build" / "compare"
TOOTHFUSE = ROOT / "target" / "release" / "toothfuse"
ICP_EXAMPLE = ROOT / "target" / "release" / "examples" / "icp_compare"
ICP_ROUNDS = 5
FUSE_ROUNDS = 3
FUSE_CASE = "f901_upper"


def cpu_of_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd: list, env: dict | None = None) -> tuple[float, float]:
    """Runs a command to completion; returns its wall time and its CPU time (user + system,
    all threads), in seconds."""
    t0, c0 = time.perf_counter(), cpu_of_children()
    p = subprocess.run([str(c) for c in cmd], env=env, capture_output=True, text=True)
    elapsed, cpu = time.perf_counter() - t0, cpu_of_children() - c0
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(map(str, cmd))}\n{p.stderr[-3000:]}")
    return elapsed, cpu


def open3d_missing() -> str | None:
    """Why Open3D cannot be imported in this interpreter, or None when it can."""
    p = subprocess.run([sys.executable, "-c", "import open3d"], capture_output=True, text=True)
    return None if p.returncode == 0 else (p.stderr.strip().splitlines() or ["?"])[-1]


def tre(est_cbct_to_ios: np.ndarray, truth_cbct_to_ios: np.ndarray, pts: np.ndarray):
    """Per-tooth TRE over `pts` (CBCT frame): (mean, RMS) of |E p - T p|, mm."""
    h = np.c_[pts, np.ones(len(pts))]
    d = np.linalg.norm(h @ (est_cbct_to_ios - truth_cbct_to_ios).T, axis=1)
    return d.mean(), np.sqrt((d * d).mean())


def tre_cell(per_tooth: list) -> str:
    mean, rms = np.mean(per_tooth, axis=0)
    return f"{mean:.3f} / {rms:.3f}"


def spread(values: list) -> str:
    return f"{statistics.median(values):.1f} ({min(values):.1f}–{max(values):.1f})"


def ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}"


# --- 1. ICP on identical point sets ---------------------------------------------------------

def icp_sides(skip_open3d: str | None) -> dict:
    """Command and environment of each side of the ICP comparison."""
    icp_dir = OUT / "icp"
    sides = {"toothfuse": ([ICP_EXAMPLE, "run", icp_dir], None)}
    if not skip_open3d:
        script = [sys.executable, HERE / "icp_open3d.py", icp_dir]
        default = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
        sides["open3d"] = (script, default)
        sides["open3d_1thread"] = (script, {**default, "OMP_NUM_THREADS": "1"})
    return sides


def icp_comparison(foreign: Path, skip_open3d: str | None) -> list:
    icp_dir = OUT / "icp"
    icp_dir.mkdir(parents=True, exist_ok=True)
    run([ICP_EXAMPLE, "export", icp_dir, foreign / "f901_upper", foreign / "f902_lower"])
    manifest = json.loads((icp_dir / "manifest.json").read_text())
    sides = icp_sides(skip_open3d)
    results = {name: [] for name in sides}
    for r in range(ICP_ROUNDS):
        order = list(sides) if r % 2 == 0 else list(reversed(sides))
        for name in order:
            cmd, env = sides[name]
            out = icp_dir / f"result_{name}_{r}.json"
            run(cmd + [out], env)
            results[name].append(json.loads(out.read_text())["cases"])
    rows = []
    for c, case in enumerate(manifest["cases"]):
        teeth = case["teeth"]
        title = (f"ICP, {case['name']} ({len(teeth)} teeth, "
                 f"{sum(t['source_points'] for t in teeth) / 1e3:.0f}k IOS points)")

        def per_iteration(name: str) -> float:
            return statistics.median(
                sum(t["loop_ms"] for t in rnd[c]["teeth"])
                / sum(t["iterations"] for t in rnd[c]["teeth"]) for rnd in results[name])

        def per_call(name: str) -> float:
            return statistics.median(
                np.mean([t["call_ms"] for t in rnd[c]["teeth"]]) for rnd in results[name])

        def tres(ios_to_cbct: list) -> list:
            return [tre(np.linalg.inv(np.reshape(m, (4, 4))),
                        np.reshape(t["truth_cbct_to_ios"], (4, 4)),
                        np.fromfile(icp_dir / t["dir"] / "eval.f64", "<f8").reshape(-1, 3))
                    for m, t in zip(ios_to_cbct, teeth)]

        def estimates(name: str) -> list:
            return [e["ios_to_cbct"] for e in results[name][0][c]["teeth"]]

        start = tres([np.fromfile(icp_dir / t["dir"] / "initial.f64", "<f8") for t in teeth])
        tre_measure = f"TRE mean / RMS (mm), from {tre_cell(start)} at the start"

        if any(rnd[c]["teeth"][k]["iterations"] != manifest["iterations"]
               for rnd in results["toothfuse"] for k in range(len(teeth))):
            sys.exit(f"{case['name']}: toothfuse did not run {manifest['iterations']} iterations")
        tf_it, tf_call = per_iteration("toothfuse"), per_call("toothfuse")
        tf_tre = tres(estimates("toothfuse"))
        if skip_open3d:
            rows += [(title, "ms per iteration", f"{tf_it:.2f}", "n/a", "–"),
                     (title, tre_measure, tre_cell(tf_tre), "n/a", "–")]
            continue
        o_it, o1_it = per_iteration("open3d"), per_iteration("open3d_1thread")
        o_call = per_call("open3d")
        o_tre = tres(estimates("open3d"))
        rows += [
            (title, "ms per iteration (Open3D on all cores)", f"{tf_it:.2f}", f"{o_it:.2f}",
             ratio(tf_it, o_it)),
            (title, "ms per iteration (Open3D on 1 thread)", f"{tf_it:.2f}", f"{o1_it:.2f}",
             ratio(tf_it, o1_it)),
            (title, f"ms per tooth: index + {manifest['iterations']} iterations",
             f"{tf_call:.1f}", f"{o_call:.1f}", ratio(tf_call, o_call)),
            (title, tre_measure, tre_cell(tf_tre), tre_cell(o_tre),
             ratio(np.mean(tf_tre, axis=0)[0], np.mean(o_tre, axis=0)[0])),
        ]
    return rows


# --- 2. Whole fusion against the paper-style reference --------------------------------------

def open_edges(path: Path) -> int:
    """Boundary plus non-manifold edges of a mesh file, counted by vtkFeatureEdges."""
    reader = vtk.vtkPLYReader()
    reader.SetFileName(str(path))
    edges = vtk.vtkFeatureEdges()
    edges.SetInputConnection(reader.GetOutputPort())
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOn()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    return edges.GetOutput().GetNumberOfCells()


def fuse_scores(out_dir: Path, ios_to_cbct: dict, case: Path) -> tuple:
    """(per-tooth TRE list, watertight teeth, teeth) of one fused output folder."""
    truth = json.loads((case / "truth" / "transforms.json").read_text())["ios_from_cbct"]
    cbct = split_by_label(*read_ply(case / "cbct.ply"))
    tres = [tre(np.linalg.inv(m), np.array(truth[str(f)]), cbct[f][0])
            for f, m in ios_to_cbct.items()]
    watertight = sum(open_edges(out_dir / f"tooth_{f}.ply") == 0 for f in ios_to_cbct)
    return tres, watertight, len(ios_to_cbct)


def fuse_comparison(foreign: Path, skip_open3d: str | None) -> tuple[list, str]:
    """Table rows, and a note on where toothfuse's time went."""
    case = foreign / FUSE_CASE
    tf_out, ref_out = OUT / "fuse_toothfuse", OUT / "fuse_reference"
    sides = {"toothfuse": [TOOTHFUSE, "fuse", "--ios", case / "ios.ply", "--cbct",
                           case / "cbct.ply", "--out", tf_out]}
    if not skip_open3d:
        sides["reference"] = [sys.executable, HERE / "paper_reference.py", "--ios",
                              case / "ios.ply", "--cbct", case / "cbct.ply", "--out", ref_out]
    wall = {name: [] for name in sides}
    cpu = {name: [] for name in sides}
    for r in range(FUSE_ROUNDS):
        for name in (list(sides) if r % 2 == 0 else list(reversed(sides))):
            w, c = run(sides[name])
            wall[name].append(w)
            cpu[name].append(c)
    report = json.loads((tf_out / "report.json").read_text())
    if report["frame"] != "cbct":
        sys.exit("toothfuse report.json: expected the CBCT output frame")
    tf = fuse_scores(tf_out, {t["fdi"]: np.reshape(t["ios_to_output"], (4, 4))
                              for t in report["teeth"]}, case)
    title = f"whole fuse, {FUSE_CASE}"
    stages = report["timing_ms"]
    note = ("toothfuse's stages in its last fuse run (report.json): " + ", ".join(
        f"{k} {stages[k] / 1e3:.1f} s" for k in ("register", "cut", "stitch")) + ".")
    wall_measure = "wall time of the whole process (s): median (min–max)"
    cpu_measure = "CPU time of the whole process, all threads (s): median (min–max)"
    if skip_open3d:
        return [(title, wall_measure, spread(wall["toothfuse"]), "n/a", "–"),
                (title, cpu_measure, spread(cpu["toothfuse"]), "n/a", "–"),
                (title, "TRE mean / RMS (mm)", tre_cell(tf[0]), "n/a", "–"),
                (title, "watertight teeth (VTK)", f"{tf[1]}/{tf[2]}", "n/a", "–")], note
    ref_t = json.loads((ref_out / "transforms.json").read_text())["ios_to_cbct"]
    ref = fuse_scores(ref_out, {int(f): np.reshape(m, (4, 4)) for f, m in ref_t.items()}, case)
    med = {k: {name: statistics.median(v) for name, v in d.items()}
           for k, d in (("wall", wall), ("cpu", cpu))}
    return [
        (title, wall_measure, spread(wall["toothfuse"]), spread(wall["reference"]),
         ratio(med["wall"]["toothfuse"], med["wall"]["reference"])),
        (title, cpu_measure, spread(cpu["toothfuse"]), spread(cpu["reference"]),
         ratio(med["cpu"]["toothfuse"], med["cpu"]["reference"])),
        (title, "TRE mean / RMS (mm)", tre_cell(tf[0]), tre_cell(ref[0]),
         ratio(np.mean(tf[0], axis=0)[0], np.mean(ref[0], axis=0)[0])),
        (title, "watertight teeth (VTK)", f"{tf[1]}/{tf[2]}", f"{ref[1]}/{ref[2]}", "–"),
    ], note


def package_versions() -> str:
    found = []
    for name in ("open3d", "vtk", "scipy", "numpy"):
        try:
            found.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            found.append(f"{name} not installed")
    return ", ".join(found)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--foreign", type=Path, required=True, help="folder of the foreign jaws")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    skip_open3d = open3d_missing()
    if skip_open3d:
        print(f"Open3D cannot be imported ({skip_open3d}): its comparisons are skipped")
    load_before = os.getloadavg()[0]
    rows = icp_comparison(args.foreign, skip_open3d)
    fuse_rows, fuse_note = fuse_comparison(args.foreign, skip_open3d)
    rows += fuse_rows
    load_after = os.getloadavg()[0]
    lines = [
        f"Measured {datetime.date.today()} on {os.cpu_count()} cores, load average "
        f"{load_before:.1f} before and {load_after:.1f} after; medians of {ICP_ROUNDS} "
        f"(ICP) and {FUSE_ROUNDS} (fuse) interleaved runs; {package_versions()}."
        + (f" Open3D could not be imported ({skip_open3d}): its columns are n/a."
           if skip_open3d else ""),
        "",
        fuse_note,
        "",
        "| comparison | measure | toothfuse | Open3D / paper-style reference "
        "| toothfuse ÷ other |",
        "|---|---|---|---|---|",
    ] + [f"| {' | '.join(r)} |" for r in rows]
    text = "\n".join(lines) + "\n"
    (OUT / "results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
