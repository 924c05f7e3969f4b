#!/usr/bin/env python3
"""tools/honami_tips.py on a synthetic tips.csv: a bending wave of 1 Hz travelling downstream at
2.0 m/s, its amplitude growing linearly from 0.01 m at the first plant to 0.03 m at the last, on
a mean displacement that falls by 0.1 m a second after t = 8 s. The script must give the wave's
travel speed, the fluctuation rms A / sqrt(2) (a 1 s mean removes a 1 Hz sine) and the
drift of the mean."""
import math
import os
import re
import subprocess
import sys
import tempfile
import unittest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "tools", "honami_tips.py")
PLANTS, SPEED, FREQUENCY = 200, 2.0, 1.0


def amplitude(p):
    return 0.01 + 0.02 * p / (PLANTS - 1)


def write_run(folder):
    os.makedirs(os.path.join(folder, "vegetation_beam"))
    with open(os.path.join(folder, "vegetation_beam", "tips.csv"), "w") as f:
        f.write("time," + ",".join(f"plant_{p}" for p in range(PLANTS)) + "\n")
        for i in range(1201):
            t = 0.01 * i
            mean = 0.3 - 0.1 * max(0.0, t - 8.0)
            row = [mean + amplitude(p) * math.sin(2 * math.pi * FREQUENCY *
                                                  (t - 0.05 * p / SPEED)) for p in range(PLANTS)]
            f.write(f"{t:.2f}," + ",".join(f"{v:.9f}" for v in row) + "\n")


class HonamiTips(unittest.TestCase):
    def run_script(self, *args):
        return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True,
                              timeout=60)

    def test_travel_speed_rms_and_drift(self):
        with tempfile.TemporaryDirectory() as folder:
            write_run(folder)
            out = self.run_script(folder, "--window", "2", "7", "--window", "9", "11")
            self.assertEqual(out.returncode, 0, out.stderr)
        windows = out.stdout.split("window ")[1:]
        self.assertEqual(len(windows), 2)
        speeds = [float(v) for v in re.findall(r"speed ([0-9.]+) m/s", windows[0])]
        self.assertEqual(len(speeds), 6)
        for v in speeds:
            self.assertAlmostEqual(v, SPEED, delta=0.05)
        rms = [float(v) for v in re.search(r"fluctuation rms \[m\]\s+(.*)", windows[0])
               .group(1).split()]
        for x, value in zip([5.0, 7.5, 10.0, 12.5, 14.5, 14.95], rms):
            p = min(PLANTS - 1, round((x - 5.0) / 0.05))
            # within 3 %: the centred mean spans 101 rows (1.01 s), printed to 0.1 mm
            self.assertAlmostEqual(value, amplitude(p) / math.sqrt(2),
                                   delta=0.03 * amplitude(p) / math.sqrt(2))
        drift = [float(v) for v in re.search(r"drift of the 1 s mean \[m\]\s+(.*)", windows[0])
                 .group(1).split()]
        for value in drift:
            self.assertLess(abs(value), 1e-6)
        drift = [float(v) for v in re.search(r"drift of the 1 s mean \[m\]\s+(.*)", windows[1])
                 .group(1).split()]
        for value in drift:  # the mean falls 0.1 m/s from 8 s: -0.2 m over 9-11 s
            self.assertAlmostEqual(value, -0.2, delta=1e-6)

    def test_missing_file_and_short_window_are_named(self):
        with tempfile.TemporaryDirectory() as folder:
            out = self.run_script(folder)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("tips.csv: not found", out.stderr)
            write_run(folder)
            out = self.run_script(folder, "--window", "20", "30")
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("window 20.0-30.0 s", out.stderr)
            self.assertIn("0.0-12.0 s", out.stderr)


if __name__ == "__main__":
    unittest.main()
