#!/usr/bin/python3
"""Two builds of the project on one scene, run in turn in one session: wall time, the windows'
wall time, each participant's compute and the fluid's stage seconds, and the pair ratios.

The machines this project is timed on drift by up to a fifth within minutes, so the builds run
alternately (A B, B A, A B, ...) and each pair's ratio B / A is printed, with the median over the
pairs. With --from TIME the first build runs the scene to TIME once, writes a checkpoint there,
and every timed run restarts from it (a restart refuses changed scenario keys, so both builds
must read the scene alike; --set options are passed to every run, the checkpoint's included).

Usage:
  /usr/bin/python3 bench/scenes/compare_builds.py OLD/build/bin NEW/build/bin \\
      [--scene scenarios/honami_field] [--from 5.0] [--to 5.6] [--pairs 3] \\
      [--record none] [--set key=value ...] [--work /tmp/compare_builds]
Copy a build's bin folder before rebuilding (cp -r build/bin /tmp/binA) to keep it for the
comparison. Without --from the runs start from t = 0 and end at --to (default: the scene's
duration).
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys


def run(cosim, scene, runs_dir, end, record, sets, restart=None, checkpoint=None):
    """One `cosim run` into its own folder; returns the summary.json as a dict."""
    os.makedirs(runs_dir, exist_ok=True)
    command = [cosim, "run", scene, "--runs-dir", runs_dir, "--quiet", "--record", record]
    if end is not None:
        command += ["--set", f"duration={end}"]
    if checkpoint is not None:
        command += ["--set", f"checkpoint_interval={checkpoint}"]
    if restart is not None:
        command += ["--restart", restart]
    for item in sets:
        command += ["--set", item]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)}\nfailed ({result.returncode}):\n{result.stderr[-2000:]}")
    folders = [os.path.join(runs_dir, f) for f in os.listdir(runs_dir)]
    folders = [f for f in folders if os.path.isdir(f)]
    newest = max(folders, key=os.path.getmtime)
    with open(os.path.join(newest, "summary.json")) as f:
        return json.load(f), newest


def figures(summary):
    """The figures a run is compared by: name -> seconds."""
    out = {"wall": summary["wall_seconds"]}
    overhead = summary.get("coupling_overhead", {})
    if "windows_wall_seconds" in overhead:
        out["windows"] = overhead["windows_wall_seconds"]
    for p in summary["participants"]:
        out[p["name"]] = p["compute_seconds"]
        stages = p.get("report", {}).get("info", {}).get("stage_seconds", {})
        for stage, seconds in sorted(stages.items()):
            out[f"  {stage}"] = seconds
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("build_a", help="bin folder of the first build (the reference)")
    parser.add_argument("build_b", help="bin folder of the second build")
    parser.add_argument("--scene", default="scenarios/honami_field")
    parser.add_argument("--from", dest="start", type=float, help="restart time [s]")
    parser.add_argument("--to", dest="end", type=float, help="end time [s]")
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--record", default="none", choices=["all", "control", "none"])
    parser.add_argument("--set", dest="sets", action="append", default=[])
    parser.add_argument("--work", default="/tmp/compare_builds")
    args = parser.parse_args()
    builds = [os.path.abspath(args.build_a), os.path.abspath(args.build_b)]
    for build in builds:
        if not os.access(os.path.join(build, "cosim"), os.X_OK):
            sys.exit(f"{build}: no cosim executable here (give a build's bin folder)")
    if args.start is not None and args.end is not None and args.end <= args.start:
        sys.exit(f"--to {args.end} must be after --from {args.start}")
    if args.pairs < 1:
        sys.exit("--pairs must be at least 1")
    shutil.rmtree(args.work, ignore_errors=True)
    restart = None
    if args.start is not None:
        _, folder = run(os.path.join(builds[0], "cosim"), args.scene,
                        os.path.join(args.work, "checkpoint"), args.start, args.record,
                        args.sets, checkpoint=args.start)
        restart = folder
        print(f"checkpoint at {args.start} s: {folder}", flush=True)
    results = [[], []]
    for pair in range(args.pairs):
        order = (0, 1) if pair % 2 == 0 else (1, 0)
        for which in order:
            summary, _ = run(os.path.join(builds[which], "cosim"), args.scene,
                             os.path.join(args.work, f"{'ab'[which]}{pair}"), args.end,
                             args.record, args.sets, restart=restart)
            results[which].append(figures(summary))
            print(f"pair {pair + 1} {'AB'[which]}: wall {summary['wall_seconds']:.2f} s",
                  flush=True)
    names = [n for n in results[0][0] if all(n in r for r in results[0] + results[1])]
    print(f"\n{'':24s} {'A':>28s} {'B':>28s} {'B / A by pair':>24s} {'median':>7s}")
    for name in names:
        a = [r[name] for r in results[0]]
        b = [r[name] for r in results[1]]
        ratios = [y / x for x, y in zip(a, b) if x > 0]
        median = f"{statistics.median(ratios):.3f}" if ratios else ""
        print(f"{name:24s} {' / '.join(f'{v:.2f}' for v in a):>28s} "
              f"{' / '.join(f'{v:.2f}' for v in b):>28s} "
              f"{' / '.join(f'{r:.3f}' for r in ratios):>24s} {median:>7s}")


if __name__ == "__main__":
    main()
