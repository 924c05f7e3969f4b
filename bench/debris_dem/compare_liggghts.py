#!/usr/bin/python3
"""debris_dem against LIGGGHTS 3.8 (Debian package `liggghts`) on the settling case of
bench/debris_dem, side by side on one thread in one session.

Both codes start from the same sphere positions (written by debris_dem_compare --write-start),
drop them for --settle-steps and time --timed-steps at dt = 1e-5 s, repetitions interleaved
(debris_dem, LIGGGHTS, debris_dem, ...) so that drift of a shared machine hits both alike.
Prints sphere-steps per CPU second of the timed steps for each code, the ratio, the list
rebuilds, and a physics check (kinetic energy and contact counts at the same times).

Model match (seed 004 table 3, debris_dem defaults): Hooke normal spring K_n = 1e4 N/m that
pushes only (LIGGGHTS limitForce on = debris_dem clip_normal_force), incremental tangential
spring K_s = 4e3 N/m with Coulomb limit tan(phi) = 0.404 times the normal force, dashpots
c = 2 h sqrt(m_eff K) with h = 0.2. LIGGGHTS takes one damping constant per type pair
(hooke/stiffness, absolute_damping on), so the spheres are put into --damping-bins diameter
classes and each class pair gets the dashpot of its mean masses: within a class the damping
ratio differs from 0.2 by under 10 % (mass spread (1 + 1/bins)^3 at 5 bins, square root). The
box is the same 10 triangles (an STL mesh, fix mesh/surface). Neighbour lists: LIGGGHTS skin
5 mm (bin), checked every step, rebuilt when a sphere moved half the skin; debris_dem margin
5 mm with its own rule. Contacts: LIGGGHTS compute contact/atom counts sphere-sphere touches;
debris_dem_compare prints both sphere-sphere and wall contacts.

CPU time: debris_dem reads its process clock around the timed steps; LIGGGHTS calls
`shell` before and after the timed run, and a helper reads the LIGGGHTS process's
utime + stime from /proc (clock ticks, 10 ms).

Usage (from anywhere; needs a Release build with the debris_dem_compare target):
  cmake --build BUILD --target debris_dem_compare
  /usr/bin/python3 bench/debris_dem/compare_liggghts.py --build BUILD [--repeats 3]
"""

import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

DENSITY = 1900.0  # kg/m^3, seed 004 table 3
KN = 1.0e4  # N/m
KT = 4.0e3  # N/m
DAMPING_RATIO = 0.2
FRICTION = 0.404
DT = 1.0e-5  # s
SIDE = 0.2  # m
HEIGHT = 0.3  # m
SKIN = 5.0e-3  # m, debris_dem list_margin (r_dam of table 3)


def ensure_liggghts():
    if shutil.which("liggghts"):
        return
    apt = ["apt-get", "install", "-y", "liggghts"]
    if os.geteuid() != 0:
        if not shutil.which("sudo"):
            sys.exit("liggghts is not installed and there is neither root nor sudo")
        apt = ["sudo"] + apt
    print("installing the Debian package liggghts:", " ".join(apt), flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run(apt, check=True, env=env)


def read_start(path):
    spheres = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            x, y, z, d = (float(v) for v in line.split())
            spheres.append((x, y, z, d))
    return spheres


def sphere_mass(d):
    return DENSITY * math.pi / 6.0 * d**3


def write_liggghts_case(work, spheres, bins, settle_steps, timed_steps, report_steps):
    d_min = min(s[3] for s in spheres)
    d_max = max(s[3] for s in spheres)
    width = (d_max - d_min) / bins
    types = [min(bins, 1 + int((s[3] - d_min) / width)) if width > 0 else 1 for s in spheres]
    # Mean mass of each class (the dashpot constant of a class pair uses these).
    mass = []
    for t in range(1, bins + 1):
        m = [sphere_mass(s[3]) for s, ty in zip(spheres, types) if ty == t]
        mass.append(sum(m) / len(m) if m else sphere_mass(d_min + (t - 0.5) * width))
    wall_type = bins + 1
    ntypes = bins + 1

    def effective_mass(i, j):  # types 1-based; the wall has infinite mass
        if i == wall_type and j == wall_type:
            return mass[0]
        if i == wall_type:
            return mass[j - 1]
        if j == wall_type:
            return mass[i - 1]
        return mass[i - 1] * mass[j - 1] / (mass[i - 1] + mass[j - 1])

    def table(value):
        return " ".join(
            f"{value(i, j):.10g}" for i in range(1, ntypes + 1) for j in range(1, ntypes + 1)
        )

    lo, hi = -0.01, 0.01
    with open(os.path.join(work, "spheres.data"), "w") as f:
        f.write("debris_dem settling case: start positions of debris_dem_compare\n\n")
        f.write(f"{len(spheres)} atoms\n{ntypes} atom types\n\n")
        f.write(f"{lo} {SIDE + hi} xlo xhi\n{lo} {SIDE + hi} ylo yhi\n{lo} {HEIGHT + hi} zlo zhi\n")
        f.write("\nAtoms\n\n")
        for k, (s, t) in enumerate(zip(spheres, types), start=1):
            f.write(f"{k} {t} {s[3]!r} {DENSITY!r} {s[0]!r} {s[1]!r} {s[2]!r}\n")
    # The 10 triangles of settling_scene.hpp (floor, four walls, open top).
    a, h = SIDE, HEIGHT
    quads = [
        ((0, 0, 0), (a, 0, 0), (a, a, 0), (0, a, 0)),
        ((0, 0, 0), (a, 0, 0), (a, 0, h), (0, 0, h)),
        ((0, a, 0), (a, a, 0), (a, a, h), (0, a, h)),
        ((0, 0, 0), (0, a, 0), (0, a, h), (0, 0, h)),
        ((a, 0, 0), (a, a, 0), (a, a, h), (a, 0, h)),
    ]
    with open(os.path.join(work, "box.stl"), "w") as f:
        f.write("solid box\n")
        for p0, p1, p2, p3 in quads:
            for tri in ((p0, p1, p2), (p0, p2, p3)):
                f.write("facet normal 0 0 0\nouter loop\n")
                for v in tri:
                    f.write(f"vertex {v[0]} {v[1]} {v[2]}\n")
                f.write("endloop\nendfacet\n")
        f.write("endsolid box\n")
    mark = f"shell {sys.executable} {os.path.abspath(__file__)} --cpu-mark {work}/cpu_marks.txt"
    gamma_n = table(lambda i, j: 2 * DAMPING_RATIO * math.sqrt(effective_mass(i, j) * KN))
    gamma_t = table(lambda i, j: 2 * DAMPING_RATIO * math.sqrt(effective_mass(i, j) * KT))
    # The pair style takes the model settings after the model, the wall after its meshes.
    settings = "absolute_damping on limitForce on"
    model = "model hooke/stiffness tangential history"
    deck = f"""# debris_dem settling case (bench/debris_dem/compare_liggghts.py)
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
read_data spheres.data
neighbor {SKIN} bin
neigh_modify every 1 delay 0 check yes
fix m1 all property/global kn peratomtypepair {ntypes} {table(lambda i, j: KN)}
fix m2 all property/global kt peratomtypepair {ntypes} {table(lambda i, j: KT)}
fix m3 all property/global gamman_abs peratomtypepair {ntypes} {gamma_n}
fix m4 all property/global gammat_abs peratomtypepair {ntypes} {gamma_t}
fix m5 all property/global coefficientFriction peratomtypepair {ntypes} {table(lambda i, j: FRICTION)}
pair_style gran {model} {settings}
pair_coeff * *
timestep {DT}
fix box all mesh/surface file box.stl type {wall_type}
fix walls all wall/gran {model} mesh n_meshes 1 meshes box {settings}
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0
fix integr all nve/sphere
compute rke all erotate/sphere
compute touching all contact/atom
compute contacts all reduce sum c_touching
thermo_style custom step time atoms ke c_rke c_contacts
thermo_modify lost error norm no
thermo {report_steps}
run {settle_steps}
{mark} before
run {timed_steps}
{mark} after
"""
    with open(os.path.join(work, "in.settling"), "w") as f:
        f.write(deck)
    return types


def cpu_mark(path, label):
    """Called through LIGGGHTS' shell command: append the CPU seconds of the LIGGGHTS process."""
    pid = os.getppid()
    while pid > 1:
        with open(f"/proc/{pid}/comm") as f:
            comm = f.read().strip()
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        if comm.startswith("liggghts"):
            ticks = int(fields[11]) + int(fields[12])  # utime + stime (stat fields 14, 15)
            with open(path, "a") as out:
                out.write(f"{label} {ticks / os.sysconf('SC_CLK_TCK')}\n")
            return
        pid = int(fields[1])  # parent pid (stat field 4)
    sys.exit("cpu-mark: no liggghts ancestor")


def run_liggghts(work, timed_steps):
    marks = os.path.join(work, "cpu_marks.txt")
    if os.path.exists(marks):
        os.remove(marks)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    out = subprocess.run(
        ["liggghts", "-in", "in.settling", "-log", "none"],
        cwd=work, env=env, capture_output=True, text=True, check=True,
    ).stdout
    with open(marks) as f:
        t = dict(line.split() for line in f)
    cpu = float(t["after"]) - float(t["before"])
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on 1 procs for (\d+) steps", out)
    builds = re.findall(r"Neighbor list builds = (\d+)", out)
    states = []
    for line in out.splitlines():
        f = line.split()
        if len(f) == 6 and f[0].isdigit():
            try:
                step, time, _, ke, rke, contacts = int(f[0]), *map(float, f[1:])
            except ValueError:
                continue
            if not states or states[-1][0] != step:
                states.append((step, time, ke, ke + rke, contacts / 2.0))
    return {
        "cpu": cpu,
        "wall": float(loops[-1][0]),
        "rebuilds": int(builds[-1]),
        "states": states,
        "log": out,
    }


def run_debris(binary, start, settle_steps, timed_steps, report_steps):
    out = subprocess.run(
        [binary, "--start", start, "--settle-steps", str(settle_steps), "--timed-steps",
         str(timed_steps), "--report-steps", str(report_steps)],
        capture_output=True, text=True, check=True,
    ).stdout
    states = []
    timed = None
    for line in out.splitlines():
        kv = dict(item.split("=") for item in line.split()[1:])
        if line.startswith("state"):
            states.append((round(float(kv["t"]) / DT), float(kv["t"]), float(kv["ke_trans"]),
                           float(kv["ke_total"]), float(kv["sphere_contacts"]),
                           float(kv["wall_contacts"])))
        elif line.startswith("timed"):
            timed = kv
    return {
        "cpu": float(timed["cpu_s"]),
        "wall": float(timed["wall_s"]),
        "rebuilds": int(timed["rebuilds"]),
        "states": states,
    }


def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--cpu-mark":
        cpu_mark(sys.argv[2], sys.argv[3])
        return
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.path.join(here, "..", "..", "build"),
                        help="CMake build folder holding bin/debris_dem_compare")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--spheres", type=int, default=5000)
    parser.add_argument("--settle-steps", type=int, default=15000)
    parser.add_argument("--timed-steps", type=int, default=4000)
    parser.add_argument("--report-steps", type=int, default=1000)
    parser.add_argument("--damping-bins", type=int, default=5)
    parser.add_argument("--keep", help="write the cases and logs into this folder")
    args = parser.parse_args()
    binary = os.path.join(args.build, "bin", "debris_dem_compare")
    if not os.access(binary, os.X_OK):
        sys.exit(f"{binary} not found: cmake --build {args.build} --target debris_dem_compare")
    ensure_liggghts()
    work = args.keep or tempfile.mkdtemp(prefix="dem_vs_liggghts_")
    os.makedirs(work, exist_ok=True)
    start = os.path.join(work, "start.txt")
    subprocess.run([binary, "--write-start", start, "--spheres", str(args.spheres)], check=True)
    spheres = read_start(start)
    write_liggghts_case(work, spheres, args.damping_bins, args.settle_steps, args.timed_steps,
                        args.report_steps)
    version = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", "liggghts"],
                             capture_output=True, text=True).stdout or "?"
    print(f"case: {len(spheres)} spheres, drop {args.settle_steps} steps, timed "
          f"{args.timed_steps} steps of {DT} s, one thread each; liggghts {version}; "
          f"files in {work}", flush=True)
    dem_runs, lig_runs = [], []
    for r in range(args.repeats):
        dem_runs.append(run_debris(binary, start, args.settle_steps, args.timed_steps,
                                   args.report_steps))
        lig_runs.append(run_liggghts(work, args.timed_steps))
        if r == 0:
            with open(os.path.join(work, "liggghts.log"), "w") as f:
                f.write(lig_runs[-1]["log"])
        steps = len(spheres) * args.timed_steps
        print(f"repeat {r + 1}: debris_dem {steps / dem_runs[-1]['cpu'] / 1e6:.2f} M/cpu-s "
              f"({dem_runs[-1]['rebuilds']} rebuilds), LIGGGHTS "
              f"{steps / lig_runs[-1]['cpu'] / 1e6:.2f} M/cpu-s "
              f"({lig_runs[-1]['rebuilds']} rebuilds)", flush=True)

    steps = len(spheres) * args.timed_steps
    print("\nsphere-steps per CPU second of the timed steps (median of "
          f"{args.repeats}; min-max):")
    rows = []
    for name, runs in (("debris_dem", dem_runs), ("LIGGGHTS 3.8", lig_runs)):
        rates = [steps / run["cpu"] for run in runs]
        wall_rates = [steps / run["wall"] for run in runs]
        rows.append(median(rates))
        print(f"  {name:13s} {median(rates) / 1e6:6.3f} M  ({min(rates) / 1e6:.3f}-"
              f"{max(rates) / 1e6:.3f}); per wall second {median(wall_rates) / 1e6:.3f} M; "
              f"list rebuilds {sorted({run['rebuilds'] for run in runs})}")
    pair_ratios = [lig["cpu"] / dem["cpu"] for dem, lig in zip(dem_runs, lig_runs)]
    print(f"  ratio debris_dem / LIGGGHTS: {rows[0] / rows[1]:.3f} (pair by pair "
          f"{', '.join(f'{x:.3f}' for x in pair_ratios)})")

    # Physics check: the same drop should give the same kinetic energy history and contacts of
    # the same order (not bitwise: different damping per pair, integrators and round-off).
    print("\nphysics check (first repeat): t, kinetic energy (J, translational + rotational), "
          "sphere-sphere contacts (debris_dem also wall contacts)")
    lig = {s[0]: s for s in lig_runs[0]["states"]}
    worst_ke = 0.0
    worst_contacts = 0.0
    for s in dem_runs[0]["states"]:
        other = lig.get(s[0])
        if other is None:
            continue
        print(f"  t={s[1]:.3f}  KE debris_dem {s[3]:.3e}  LIGGGHTS {other[3]:.3e}   contacts "
              f"debris_dem {s[4]:.0f} (+{s[5]:.0f} wall)  LIGGGHTS {other[4]:.0f}")
        if s[1] >= 0.05 - 1e-9 and s[3] > 0 and other[3] > 0:
            worst_ke = max(worst_ke, abs(math.log10(s[3] / other[3])))
        if s[4] > 100 and other[4] > 0:
            worst_contacts = max(worst_contacts, abs(math.log10(s[4] / other[4])))
    same = worst_ke < 0.5 and worst_contacts < 0.3
    print(f"  largest |log10 ratio| from t = 0.05 s: kinetic energy {worst_ke:.2f}, contacts "
          f"{worst_contacts:.2f} -> "
          + ("the same physics (same order of magnitude and trend)" if same
             else "NOT the same physics: the timing comparison is not like for like"))


if __name__ == "__main__":
    main()
