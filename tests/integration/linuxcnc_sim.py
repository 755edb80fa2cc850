#!/usr/bin/env python3
"""The emitted LinuxCNC sphere cycle on the real controller (issue 31, part 1).

LinuxCNC 2.9 in simulation, headless (tools/linuxcnc_sim/): three cycles of the sphere cycle
planned by probeloop are run by task and motion, G38.2 stops on motion.probe-input raised by a
virtual sphere that drifts with examples/truth_rigid.yaml on a clock 60 times the wall's, and
LinuxCNC writes the (LOG,...) file. probeloop evaluate must recover, per cycle, the errors the
probe component applied (EX0C ... EC0C, relative to cycle 1) within U; the drift must be larger
than U (else recovery proves nothing) and the zero hypothesis must fail; every point's
overshoot (where motion recorded it beyond the contact) stays below 1 um; no process of the
simulation is left afterwards, also when a run fails. About 2 min of wall time.

Exit 77 (ctest SKIP_RETURN_CODE) when LinuxCNC, /usr/bin/python3 with its hal and linuxcnc
modules, or PyYAML are missing. Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from linuxcnc_common import SRC, SYS_PY, TOOLS, finish_run, skip_without_linuxcnc  # noqa: E402

skip_without_linuxcnc("linuxcnc_sim")
PL = os.environ["PROBELOOP"]

check = Checks()
NAMES = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]
work = tempfile.mkdtemp(prefix="probeloop-linuxcnc-")
os.chmod(work, 0o755)
t0 = time.monotonic()
try:
    # plan -> make_config -> LinuxCNC runs the program -> LOG -> evaluate (tools/linuxcnc_sim/sphere_run.py)
    r = subprocess.run([SYS_PY, os.path.join(TOOLS, "sphere_run.py"), "--probeloop", PL, "--source-dir", SRC,
                        "--work", work, "--cycles", "3", "--seed", "1", "--timeout", "300"],
                       capture_output=True, text=True, timeout=900)
    print(r.stdout.rstrip())
    if r.stderr.strip():
        print(r.stderr.rstrip()[-3000:])
    summary_path = os.path.join(work, "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    check("LinuxCNC ran the emitted sphere cycle to its end without an error message", r.returncode == 0 and summary.get("ok"),
          json.dumps(summary.get("messages")) + "\n" + r.stderr[-1500:])
    errs = [m for m in summary.get("messages") or [] if m["kind"] == "error"]
    check("no error message from LinuxCNC", not errs, json.dumps(errs))
    check("LinuxCNC logged 3 cycles x 5 spheres x 5 points = 75 points, one per contact",
          summary.get("points_logged") == 75 and summary.get("contacts") == 75,
          f"points {summary.get('points_logged')}, contacts {summary.get('contacts')}")
    check("probeloop evaluate read LinuxCNC's log", summary.get("evaluate_rc") == 0, summary.get("evaluate_error", ""))

    errors_csv, truth_json = os.path.join(work, "eval", "errors.csv"), os.path.join(work, "truth.json")
    compare = os.path.join(SRC, "tests", "integration", "compare_errors.py")
    if os.path.exists(errors_csv) and os.path.exists(truth_json):
        c = subprocess.run([sys.executable, compare, errors_csv, truth_json, "0", "0", "--within-U"],
                           capture_output=True, text=True)
        print("   " + c.stdout.strip().replace("\n", "\n   "))
        check("every cycle's EX0C ... EC0C recovered within U (the errors the virtual sphere applied)",
              c.returncode == 0, c.stdout)
        # The recovery must mean something: the drift exceeds U in cycle 3, so zero errors do not pass.
        truth = json.load(open(truth_json))["cycles"]
        rows = [line for line in open(errors_csv) if not line.startswith("#")]
        last = list(csv.DictReader(rows))[-1]
        beyond = [n for n in NAMES if abs(truth[-1][n]) > float(last["U_" + n])]
        check("the injected drift exceeds U in the last cycle (for at least 4 of the 7 errors)", len(beyond) >= 4,
              f"beyond U: {beyond}")
        zero = os.path.join(work, "truth_zero.json")
        json.dump({"cycles": [{"cycle": t["cycle"], **dict.fromkeys(NAMES, 0.0)} for t in truth]}, open(zero, "w"))
        z = subprocess.run([sys.executable, compare, errors_csv, zero, "0", "0", "--within-U"], capture_output=True, text=True)
        check("a sphere that did not drift is refused by the same comparison", z.returncode == 1, z.stdout)
    else:
        check("errors.csv and truth.json were written", False, work)

    ov = summary.get("overshoot_um") or {}
    check("every contact recorded less than 1 um beyond the surface (servo-thread trigger, 100 us servo period)",
          ov and 0.0 <= ov["min"] and ov["max"] < 1.0, json.dumps(ov))
finally:
    # sphere_run.py stops LinuxCNC itself, also on errors; should it have been killed, stop it here
    finish_run(check, work, t0)
check.finish()
