#!/usr/bin/python3
"""fluid_mps against MPS-Basic (github MPS-Basic/MPS-Basic) on the Martin & Moyce dam break,
side by side on one thread in one session.

MPS-Basic is built from its public source tree at --mps-basic (outside this repository; nothing
of it is copied here) by bench/fluid_mps/mps_basic/CMakeLists.txt, which add_subdirectory()s
MPS-Basic's own CMakeLists.txt (its target `mps`, unchanged) and builds `mps_basic_driver`: the
same sources without main.cpp plus mps_basic/driver.cpp, which loads an MPS-Basic input with
MPS-Basic's Loader and MPSFactory and times MPS::stepForward(). One file,
pressure_poisson_equation.cpp, is compiled for the driver with mps_basic/solver_probe.hpp
force-included: it sets the BiCGSTAB tolerance and counts its iterations, nothing else.

Case: our dam_break(p, a, 2a, 8a, 3a) scene (a = 0.05715 m, 2 wall + 2 dummy layers,
l0 = a / N for N in --sizes); bench_fluid_mps_compare --write-start writes the particles and
this script turns them into MPS-Basic's input.prof + settings.yml, so both codes start from the
same particles with the same radii, tolerance, dt, gravity, viscosity, compressibility,
relaxation, surface threshold and collision constants. Both run --warmup-time untimed (the
column is collapsing when timing starts), then --steps timed steps; CPU seconds are the process
clock (CLOCK_PROCESS_CPUTIME_ID) around the timed steps only, in both programs. Repetitions
are interleaved (the order alternates) with OMP_NUM_THREADS=1, OMP_WAIT_POLICY=passive.

Usage:
  /usr/bin/python3 bench/fluid_mps/compare_mps_basic.py --mps-basic /path/to/MPS-Basic \\
      [--build /work/main/build] [--sizes 20,40,80] [--repeats 3] [--steps 200]
      [--tolerance 1e-8] [--preconditioner automatic] [--native-tolerance] [--check]
MPS-Basic's CMake fetches Eigen, yaml-cpp, fast-cpp-csv-parser, argparse and googletest with
FetchContent. Without network give local trees: --deps DIR with subfolders yaml-cpp,
fast-cpp-csv-parser, argparse (checked out at MPS-Basic's pinned commits), optionally eigen and
googletest; missing eigen falls back to the system Eigen (/usr/include/eigen3), missing
googletest to /usr/src/googletest.
"""

import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
COLUMN = 0.05715  # a [m]
GRAVITY = 9.81
DENSITY = 1000.0
VISCOSITY = 1.0e-6
COMPRESSIBILITY = 0.45e-9
RELAXATION = 0.2
SURFACE_THRESHOLD = 0.97
COLLISION_RATIO = 0.5
RESTITUTION = 0.2
RADII = (2.1, 2.1, 4.0)  # number density, gradient, Laplacian [l0]: fluid_mps defaults

UNMATCHED = """Settings that are not the same in both codes (everything else listed above is):
- Pressure solver: fluid_mps conjugate gradients (preconditioner {pre}), warm start from the
  last pressure, unknowns = fluid and wall particles off the free surface. MPS-Basic: Eigen
  BiCGSTAB with Eigen's diagonal preconditioner, zero start, the full N x N system (identity rows
  for surface and dummy particles). One BiCGSTAB iteration costs two matrix-vector products and
  two preconditioner applications, one CG iteration one of each: the iteration counts are not
  equal work.
- Tolerance: both stop at |b - A x| / |b| < {tol:g}. MPS-Basic as published keeps Eigen's default,
  machine epsilon (2.2e-16); solver_probe.hpp sets {tol:g} for the equal-tolerance columns
  (--native-tolerance adds MPS-Basic at its own default).
- Collision (same d_c = {cr} l0, restitution {rs}): fluid_mps uses seed 001's form (pair
  velocity change from the pre-collision velocities, position moved by dt times it, walls fixed);
  MPS-Basic applies impulses pair by pair in sequence and also pushes the pair apart by the
  overlap, moving wall particles as well.
- Surface detection: both n* < {beta} n0 only; MPS-Basic's particle-distribution sub-criterion
  (on in its dam-break example) is switched off.
- Neighbours: fluid_mps keeps a pair list with a 0.5 l0 skin; MPS-Basic searches its buckets three
  times per step (algorithm, not a setting).
- Build: MPS-Basic pins Eigen 5.0.0; here it gets {eigen} (fluid_mps uses the system Eigen 3.4).
  MPS-Basic C++17 (its own standard), fluid_mps C++20, both CMake Release (-O3 -DNDEBUG),
  same compiler. MPS-Basic's googletest (only for its tests) is the local one.
- fluid_mps normally takes dt from stable_dt(); here both step the same fixed dt. MPS-Basic's
  example has g = 9.8 and radii 3.1 / 2.1 / 3.1 l0; here g = {g} and radii {radii} l0 in both."""


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, **kw)


def ensure_ours(build):
    exe = os.path.join(build, "bin", "bench_fluid_mps_compare")
    if not os.path.exists(exe):
        run(["cmake", "--build", build, "--target", "bench_fluid_mps_compare", "-j2"])
    return exe


def ensure_mps_basic(source, build_dir, deps, rebuild):
    driver = os.path.join(build_dir, "mps_basic_driver")
    if os.path.exists(driver) and not rebuild:
        return driver, describe_eigen(build_dir)
    if not os.path.exists(os.path.join(source, "src", "mps.cpp")):
        sys.exit(f"--mps-basic {source}: not an MPS-Basic source tree (no src/mps.cpp)")
    os.makedirs(build_dir, exist_ok=True)
    flags = [
        "-DCMAKE_BUILD_TYPE=Release",
        f"-DMPS_BASIC_SOURCE_DIR={os.path.abspath(source)}",
        "-DYAML_CPP_BUILD_TESTS=OFF",
        "-DYAML_CPP_BUILD_TOOLS=OFF",
        "-DARGPARSE_BUILD_TESTS=OFF",
        "-DARGPARSE_BUILD_SAMPLES=OFF",
    ]
    local = 0
    for name in ("yaml-cpp", "fast-cpp-csv-parser", "argparse", "eigen", "googletest"):
        path = os.path.join(deps, name) if deps else ""
        if not (path and os.path.isdir(path)):
            path = ""
        if not path and name == "eigen" and os.path.isdir("/usr/include/eigen3/Eigen"):
            # Debian's Eigen headers as a FetchContent source tree (MPS-Basic only needs the
            # headers at ${eigen_SOURCE_DIR}).
            path = os.path.join(build_dir, "system-eigen")
            os.makedirs(path, exist_ok=True)
            for sub in ("Eigen", "unsupported"):
                link = os.path.join(path, sub)
                if not os.path.lexists(link):
                    os.symlink(f"/usr/include/eigen3/{sub}", link)
            with open(os.path.join(path, "CMakeLists.txt"), "w") as f:
                f.write("# system Eigen headers (/usr/include/eigen3), see compare_mps_basic.py\n")
        if not path and name == "googletest" and os.path.isdir("/usr/src/googletest"):
            path = "/usr/src/googletest"
        if path:
            flags.append(f"-DFETCHCONTENT_SOURCE_DIR_{name.upper()}={os.path.abspath(path)}")
            local += 1
    if local == 5:
        flags.append("-DFETCHCONTENT_FULLY_DISCONNECTED=ON")
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    run(["cmake", "-S", os.path.join(HERE, "mps_basic"), "-B", build_dir] + generator + flags)
    run(["cmake", "--build", build_dir, "--target", "mps", "mps_basic_driver", "-j2"])
    return driver, describe_eigen(build_dir)


def describe_eigen(build_dir):
    cache = os.path.join(build_dir, "CMakeCache.txt")
    try:
        with open(cache) as f:
            for line in f:
                if line.startswith("FETCHCONTENT_SOURCE_DIR_EIGEN"):
                    path = line.split("=", 1)[1].strip()
                    headers = os.path.realpath(os.path.join(path, "Eigen"))
                    if headers.startswith("/usr/include/eigen3"):
                        return "the system Eigen 3.4 headers (Debian libeigen3-dev)"
                    return f"the Eigen at {path}"
    except OSError:
        pass
    return "the Eigen its CMake fetched"


def default_dt(l0):
    return 0.25 * l0 / math.sqrt(2.0 * GRAVITY * 2.0 * COLUMN)  # as compare_case.cpp


def yaml_float(x):
    return f"{x:.16e}"  # MPS-Basic reads numbers without a decimal point as strings


def write_mps_basic_case(work, start_file, l0, dt, end_time, tolerance_note):
    particles, domain = [], None
    with open(start_file) as f:
        for line in f:
            if line.startswith("# domain"):
                domain = [float(v) for v in line.split()[2:]]
            elif line.startswith("#") or not line.strip():
                continue
            else:
                kind, x, y, z = line.split()
                particles.append((int(kind), x, y, z))
    with open(os.path.join(work, "input.prof"), "w") as f:
        f.write(f"0\n{len(particles)}\n")
        for kind, x, y, z in particles:  # MPS-Basic: 1 fluid, 2 wall, 3 dummy wall
            f.write(f"{kind} {x} {y} {z} 0 0 0\n")
    rn, rg, rl = RADII
    settings = f"""# fluid_mps dam break for MPS-Basic (bench/fluid_mps/compare_mps_basic.py)
# {tolerance_note}
dim: 2
particleDistance: {yaml_float(l0)}
dt: {yaml_float(dt)}
endTime: {yaml_float(end_time)}
outputPeriod: {yaml_float(end_time)}
cflCondition: 0.3
numPhysicalCores: 1
domainMin: [{yaml_float(domain[0])}, {yaml_float(domain[1])}, 0.0]
domainMax: [{yaml_float(domain[2])}, {yaml_float(domain[3])}, 0.0]
defaultDensity: {yaml_float(DENSITY)}
kinematicViscosity: {yaml_float(VISCOSITY)}
xyz-input: true
gravity: [0.0, {yaml_float(-GRAVITY)}, 0.0]
gravity-norm: {yaml_float(GRAVITY)}
gravity-angle: 0.0
surfaceDetection-numberDensity-threshold: {yaml_float(SURFACE_THRESHOLD)}
surfaceDetection-particleDistribution: false
surfaceDetection-particleDistribution-threshold: 1.0
pressureCalculationMethod: Implicit
compressibility: {yaml_float(COMPRESSIBILITY)}
relaxationCoefficientForPressure: {yaml_float(RELAXATION)}
soundSpeed: 17.1
collisionDistanceRatio: {yaml_float(COLLISION_RATIO)}
coefficientOfRestitution: {yaml_float(RESTITUTION)}
radiusRatioForNumberDensity: {yaml_float(rn)}
radiusRatioForGradient: {yaml_float(rg)}
radiusRatioForLaplacian: {yaml_float(rl)}
particlesPath: ./input.prof
outputVtkInBinary: true
"""
    with open(os.path.join(work, "settings.yml"), "w") as f:
        f.write(settings)
    return len(particles)


def last_json(stdout, what):
    for line in reversed(stdout.splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    sys.exit(f"{what}: no JSON line in its output:\n{stdout[-2000:]}")


def env_one_thread():
    return dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")


def run_ours(exe, n, warmup, steps, dt, args):
    cmd = [exe, "--cells-per-width", str(n), "--warmup-steps", str(warmup), "--steps", str(steps),
           "--dt", repr(dt), "--tolerance", repr(args.tolerance),
           "--preconditioner", args.preconditioner, "--radii", ",".join(map(str, RADII)),
           "--surface-threshold", repr(SURFACE_THRESHOLD), "--gravity", repr(GRAVITY)]
    out = run(cmd, capture_output=True, text=True, env=env_one_thread())
    return last_json(out.stdout, "bench_fluid_mps_compare")


def run_theirs(driver, case, warmup, steps, tolerance, final=None):
    output = tempfile.mkdtemp(prefix="out-", dir=case)
    cmd = [driver, "--setting", os.path.join(case, "settings.yml"), "--output", output,
           "--warmup-steps", str(warmup), "--steps", str(steps), "--tolerance", repr(tolerance)]
    if final:
        cmd += ["--write-final", final]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env_one_thread())
    shutil.rmtree(output, ignore_errors=True)
    if out.returncode != 0:
        sys.exit(f"mps_basic_driver failed ({out.returncode}):\n{out.stdout[-2000:]}\n"
                 f"{out.stderr[-2000:]}")
    result = last_json(out.stdout, "mps_basic_driver")
    result["stderr_lines"] = len(out.stderr.splitlines())
    return result


def read_prof(path):
    with open(path) as f:
        f.readline()
        count = int(f.readline())
        rows = [f.readline().split() for _ in range(count)]
    return [(int(r[0]), float(r[1]), float(r[2])) for r in rows]


def check_driver(source_build, driver, case, steps, dt):
    """The driver steps exactly as MPS-Basic's own program: run both at MPS-Basic's native
    tolerance for `steps` steps and compare the particles (its prof has 6 digits)."""
    mps = os.path.join(source_build, "mps-basic", "mps")
    settings = os.path.join(case, "settings.yml")
    check = os.path.join(case, "check")
    os.makedirs(check, exist_ok=True)
    with open(settings) as f:
        text = f.read()
    end = (steps - 0.5) * dt  # `while (time < endTime)`: exactly `steps` steps, saved at the end
    lines = []
    for line in text.splitlines():
        if line.startswith("endTime:") or line.startswith("outputPeriod:"):
            line = line.split(":")[0] + f": {yaml_float(end)}"
        lines.append(line)
    shutil.copy(os.path.join(case, "input.prof"), check)
    with open(os.path.join(check, "settings.yml"), "w") as f:
        f.write("\n".join(lines) + "\n")
    out_dir = os.path.join(check, "result")
    shutil.rmtree(out_dir, ignore_errors=True)
    os.makedirs(out_dir)
    run([mps, "--setting", os.path.join(check, "settings.yml"), "--output", out_dir],
        capture_output=True, text=True, env=env_one_thread())
    theirs = read_prof(os.path.join(out_dir, "prof", "output_0001.prof"))
    final = os.path.join(check, "driver_final.prof")
    run_theirs(driver, check, 0, steps, 0.0, final)
    ours = read_prof(final)
    diff = max(max(abs(a[1] - b[1]), abs(a[2] - b[2])) for a, b in zip(theirs, ours))
    same_types = all(a[0] == b[0] for a, b in zip(theirs, ours)) and len(theirs) == len(ours)
    return diff, same_types


def summary(values):
    med = statistics.median(values)
    return med, min(values), max(values)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mps-basic", required=True, help="MPS-Basic source tree (outside the repo)")
    ap.add_argument("--mps-basic-build", help="its build dir (default MPS_BASIC/build-compare)")
    ap.add_argument("--deps", help="local FetchContent trees for MPS-Basic "
                    "(default: MPS_BASIC/../deps if it exists)")
    ap.add_argument("--rebuild", action="store_true", help="reconfigure and rebuild MPS-Basic")
    ap.add_argument("--build", default="/work/main/build", help="our CMake build dir")
    ap.add_argument("--sizes", default="20,40,80", help="a / l0 values (2k, 5.5k, 20k particles)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--warmup-time", type=float, default=0.05, help="untimed time [s]")
    ap.add_argument("--steps", type=int, default=200, help="timed steps per run")
    ap.add_argument("--tolerance", type=float, default=1e-8)
    ap.add_argument("--preconditioner", default="automatic",
                    choices=["automatic", "amg", "jacobi", "ic", "aggregation"], help="fluid_mps' PCG")
    ap.add_argument("--native-tolerance", action="store_true",
                    help="also time MPS-Basic at its own tolerance (Eigen default, 2.2e-16)")
    ap.add_argument("--check", action="store_true", help="first check that mps_basic_driver "
                    "steps exactly as MPS-Basic's own `mps` (smallest size, 20 steps)")
    ap.add_argument("--work", help="folder for the generated cases (default: a temporary one)")
    args = ap.parse_args()

    source = os.path.abspath(args.mps_basic)
    build_dir = os.path.abspath(args.mps_basic_build or os.path.join(source, "build-compare"))
    deps = args.deps or os.path.join(os.path.dirname(source), "deps")
    ours = ensure_ours(os.path.abspath(args.build))
    driver, eigen = ensure_mps_basic(source, build_dir, deps if os.path.isdir(deps) else None,
                                     args.rebuild)
    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    work = args.work or tempfile.mkdtemp(prefix="compare_mps_basic-")
    os.makedirs(work, exist_ok=True)
    try:
        commit = subprocess.run(["git", "-C", source, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip() or "unknown"
    except OSError:
        commit = "unknown"

    rn, rg, rl = RADII
    print(f"MPS-Basic {source} (commit {commit}), driver {driver}")
    print(f"fluid_mps {ours}")
    print(f"Case: dam_break a = {COLUMN} m, column a x 2a, tank 8a x 3a, 2 wall + 2 dummy layers; "
          f"dt = 0.25 l0 / sqrt(2 g 2a) fixed; untimed to t = {args.warmup_time} s, then "
          f"{args.steps} timed steps; {args.repeats} interleaved repetitions, 1 thread.")
    print(f"Both: radii {rn} / {rg} / {rl} l0 (density / gradient / Laplacian), relative residual "
          f"tolerance {args.tolerance:g}, g = {GRAVITY}, nu = {VISCOSITY:g}, rho = {DENSITY:g}, "
          f"compressibility {COMPRESSIBILITY:g} 1/Pa, density source with relaxation "
          f"{RELAXATION}, surface n* < {SURFACE_THRESHOLD} n0, collision {COLLISION_RATIO} l0 / "
          f"{RESTITUTION}. fluid_mps preconditioner: {args.preconditioner}.", flush=True)

    cases = {}
    for n in sizes:
        l0 = COLUMN / n
        dt = default_dt(l0)
        warmup = int(round(args.warmup_time / dt))
        case = os.path.join(work, f"a_over_l0_{n}")
        os.makedirs(case, exist_ok=True)
        start = os.path.join(case, "start.txt")
        run([ours, "--cells-per-width", str(n), "--write-start", start])
        count = write_mps_basic_case(case, start, l0, dt, (warmup + args.steps) * dt,
                                     f"tolerance {args.tolerance:g} set by mps_basic_driver")
        cases[n] = dict(l0=l0, dt=dt, warmup=warmup, dir=case, particles=count)

    if args.check:
        n = sizes[0]
        diff, same = check_driver(build_dir, driver, cases[n]["dir"], 20, cases[n]["dt"])
        print(f"Check a/l0 = {n}, 20 steps, Eigen default tolerance: mps_basic_driver against "
              f"MPS-Basic's own mps: max position difference {diff:.2e} m (prof files print 6 "
              f"digits), particle types {'equal' if same else 'DIFFER'}.", flush=True)

    results = {n: {"ours": [], "theirs": [], "native": []} for n in sizes}
    for r in range(args.repeats):
        for n in sizes:
            c = cases[n]
            order = ["ours", "theirs"] if r % 2 == 0 else ["theirs", "ours"]
            if args.native_tolerance:
                order.append("native")
            for who in order:
                if who == "ours":
                    res = run_ours(ours, n, c["warmup"], args.steps, c["dt"], args)
                elif who == "theirs":
                    res = run_theirs(driver, c["dir"], c["warmup"], args.steps, args.tolerance)
                else:
                    res = run_theirs(driver, c["dir"], c["warmup"], args.steps, 0.0)
                res["rate"] = res["particles"] * res["steps"] / res["cpu_s"]
                results[n][who].append(res)
                print(f"  repeat {r + 1} a/l0={n} {res['code']}"
                      f"{' (native tol)' if who == 'native' else ''}: "
                      f"{res['rate'] / 1e6:.3f} M particle-steps/CPU s, "
                      f"{1e3 * res['cpu_s'] / res['steps']:.2f} ms/step CPU, "
                      f"{res['mean_iterations']:.1f} it/step, front {res['front_x']:.4f} m",
                      flush=True)

    print()
    print("Particle-steps per CPU second of the timed steps (median over repetitions, min-max); "
          "iterations = mean pressure-solver iterations per step")
    head = ("| a/l0 | particles | fluid_mps rate | fluid_mps it/step | MPS-Basic rate | "
            "MPS-Basic it/step | ratio fluid_mps / MPS-Basic | front x at t_end (ours / theirs)"
            " |")
    if args.native_tolerance:
        head += " MPS-Basic native-tol rate | it/step | ratio |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for n in sizes:
        o, t = results[n]["ours"], results[n]["theirs"]
        ro, rt = summary([x["rate"] for x in o]), summary([x["rate"] for x in t])
        ratios = summary([a["rate"] / b["rate"] for a, b in zip(o, t)])
        row = (f"| {n} | {o[0]['particles']} | {ro[0] / 1e6:.3f} M ({ro[1] / 1e6:.3f}-"
               f"{ro[2] / 1e6:.3f}) | {statistics.median(x['mean_iterations'] for x in o):.1f} | "
               f"{rt[0] / 1e6:.3f} M ({rt[1] / 1e6:.3f}-{rt[2] / 1e6:.3f}) | "
               f"{statistics.median(x['mean_iterations'] for x in t):.1f} | "
               f"{ro[0] / rt[0]:.2f} (pairs {ratios[1]:.2f}-{ratios[2]:.2f}) | "
               f"{o[0]['front_x']:.4f} / {t[0]['front_x']:.4f} m at t = {o[0]['t_end']:.4f} s |")
        if args.native_tolerance:
            nv = results[n]["native"]
            rn_ = summary([x["rate"] for x in nv])
            row += (f" {rn_[0] / 1e6:.3f} M | "
                    f"{statistics.median(x['mean_iterations'] for x in nv):.1f} | "
                    f"{ro[0] / rn_[0]:.2f} |")
        print(row)
    print()
    for n in sizes:
        c, t = cases[n], results[n]["theirs"][0]
        o = results[n]["ours"][0]
        print(f"a/l0 = {n}: l0 = {c['l0']:.6g} m, dt = {c['dt']:.6g} s, warm-up {c['warmup']} "
              f"steps; fluid_mps unconverged steps {o['unconverged_steps']}, neighbour searches "
              f"per step {o['searches_per_step']:.2f}; MPS-Basic worst relative residual "
              f"{t['worst_relative_residual']:.2g}, particles turned ghost "
              f"{t['ghost_particles']}, stderr lines (Courant warnings) {t['stderr_lines']}")
    print()
    print(UNMATCHED.format(pre=args.preconditioner, tol=args.tolerance, cr=COLLISION_RATIO,
                           rs=RESTITUTION, beta=SURFACE_THRESHOLD, eigen=eigen, g=GRAVITY,
                           radii=f"{rn} / {rg} / {rl}"))
    print()
    print("Rerun: /usr/bin/python3 " + " ".join([os.path.abspath(__file__)] + sys.argv[1:]))


if __name__ == "__main__":
    main()
