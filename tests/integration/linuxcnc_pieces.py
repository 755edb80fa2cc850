#!/usr/bin/env python3
"""The thermal test piece's inspection and the stepped workpiece's probing on the real controller
(issue 31, item 3).

LinuxCNC 2.9 in simulation, headless (tools/linuxcnc_sim/piece_run.py): each piece is planned for
a fast variant of parts/machines/linuxcnc_rotary_mill.yaml (shortened: fewer points and cycles,
the probing feed kept), machined on the virtual machine (probeloop simulate), and its probing
program run by LinuxCNC against the part as the VM cut it (truth.json features[].as_cut; for the
stepped workpiece seen through X/Y scale errors of 0.15 / 0.25 um/mm, the truth YAML's). LinuxCNC's
LOG is evaluated by probeloop evaluate (the stepped workpiece with the VM's CMM export).
Asserted: the program ran to its end without an error message; every planned point logged once,
one contact each, on the surface it was planned for; every overshoot (how far beyond the surface
motion recorded the tip) in 0 .. 1 um; thermal test piece: every EX, EY, EZ, EB, ETTP within U of
the VM truth (as cut) and, run without probe noise, within 0.3 um of it (which a piece that did not
move fails), the VM's own
on-machine evaluation within its U of the truth and within the combined U of LinuxCNC's; stepped
workpiece: every probed plane within the probe's repeatability (2 um) of the as-cut plane seen
through the scale field (some planes are not without the field), k_pos_x/y within U of the
injected scale errors; no LinuxCNC process left. About 4 min of wall time (LinuxCNC about 100 + 95 s of program).

Exit 77 (ctest SKIP_RETURN_CODE) when LinuxCNC, /usr/bin/python3 with its hal and linuxcnc
modules, or PyYAML are missing. Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from linuxcnc_common import SRC, SYS_PY, TOOLS, finish_run, skip_without_linuxcnc  # noqa: E402

PL = os.environ["PROBELOOP"]
TIGHT_UM = 0.3          # LinuxCNC's ETTP errors against the as-cut truth, no probe noise (um quantities)
PLANE_UM = 2.0          # the stepped workpiece's probe repeatability (2 sigma), parts/stepped_workpiece.yaml

skip_without_linuxcnc("linuxcnc_pieces")
check = Checks()
work = tempfile.mkdtemp(prefix="probeloop-linuxcnc-pieces-")
os.chmod(work, 0o755)
t0 = time.monotonic()


def run_piece(piece, *extra):
    d = os.path.join(work, piece)
    r = subprocess.run([SYS_PY, os.path.join(TOOLS, "piece_run.py"), "--probeloop", PL, "--source-dir", SRC,
                        "--work", d, "--piece", piece, "--seed", "1", "--timeout", "300", *extra],
                       capture_output=True, text=True, timeout=1200)
    print(r.stdout.rstrip())
    if r.stderr.strip():
        print(r.stderr.rstrip()[-3000:])
    p = os.path.join(d, "summary.json")
    s = json.load(open(p)) if os.path.exists(p) else {}
    name = {"ttp": "thermal test piece's inspection", "sw": "stepped workpiece's probing"}[piece]
    check(f"LinuxCNC ran the {name} program to its end", r.returncode == 0 and s.get("ok"),
          json.dumps(s.get("messages")) + "\n" + r.stderr[-1500:])
    errs = [m for m in s.get("messages") or [] if m["kind"] == "error"]
    check(f"{piece}: no error message from LinuxCNC", not errs, json.dumps(errs))
    n = s.get("points_planned")
    check(f"{piece}: every planned point logged once, one contact each ({n})",
          n and s.get("points_logged") == n and s.get("contacts") == n and s.get("planned_points_missing") == 0,
          {k: s.get(k) for k in ("points_planned", "points_logged", "contacts", "planned_points_missing")})
    check(f"{piece}: each contact on the surface of the point logged with it, none in a rapid or feed move",
          s.get("contact_order_matches_log") and s.get("contacts_without_patch") == 0
          and s.get("contacts_in_other_moves") == 0,
          {k: s.get(k) for k in ("contact_order_matches_log", "contacts_without_patch", "contacts_in_other_moves")})
    ov = s.get("overshoot_um") or {}
    check(f"{piece}: every contact recorded 0 .. 1 um beyond the surface (servo-thread trigger, 100 us)",
          ov and 0.0 <= ov["min"] and ov["max"] < 1.0, json.dumps(ov))
    check(f"{piece}: probeloop evaluate read LinuxCNC's log", s.get("evaluate_rc") == 0, s.get("evaluate_error", ""))
    return s


try:
    # without probe noise: the tight check measures the controller path (the noise, 0.25 um, moved
    # single ETTP errors by up to 0.5 um; the stepped workpiece below keeps its noise)
    s = run_piece("ttp", "--no-noise")
    comp = s.get("comparison") or []
    check("ttp: 2 cycles x 5 errors compared", len(comp) == 10, len(comp))
    bad = [c for c in comp if not c["lc_within_U"]]
    check("ttp: LinuxCNC's EX, EY, EZ, EB, ETTP within U of the VM truth (as cut)", comp and not bad, bad)
    um = [c for c in comp if c["name"].endswith("_um")]
    bad = [c for c in um if abs(c["lc_minus_truth"]) > TIGHT_UM]
    check(f"ttp: LinuxCNC's EX, EY, EZ, ETTP within {TIGHT_UM} um of the truth", um and not bad, bad)
    check(f"ttp: the truth moved more than {TIGHT_UM} um somewhere (a piece that did not move fails the check above)",
          any(abs(c["truth"]) > TIGHT_UM for c in um), [(c["name"], c["truth"]) for c in um])
    bad = [c for c in comp if not c["vm_within_U"]]
    check("ttp: the VM's own on-machine evaluation within its U of the truth", comp and not bad, bad)
    bad = [c for c in comp if not c["lc_vm_within_U"]]
    check("ttp: LinuxCNC's and the VM's evaluation agree within the combined U", comp and not bad, bad)

    s = run_piece("sw")
    planes = s.get("planes") or []
    check("sw: 21 planes probed (top, 4 x 4 walls, 4 floors)", len(planes) == 21, len(planes))
    bad = [p for p in planes if abs(p["deviation_um"]) > PLANE_UM]
    check(f"sw: every probed plane within {PLANE_UM} um of the as-cut plane seen through the scale field",
          planes and not bad, bad)
    check(f"sw: without the field some planes would be more than {PLANE_UM} um off (the field is seen)",
          any(abs(p["deviation_no_field_um"]) > PLANE_UM for p in planes), planes)
    k = s.get("k_pos") or {}
    for ax in "xy":
        q = k.get(ax)
        check(f"sw: k_pos_{ax} within U of the injected scale error", q and q["within_U"], q)
        check(f"sw: the injected k_pos_{ax} exceeds U (zero would fail)", q and abs(q["injected"]) > q["U"], q)
finally:
    # piece_run.py stops LinuxCNC itself; should it have been killed, run_program.py --cleanup
    # (under run_program.py's queue lock) stops what it left; no LinuxCNC process may remain
    finish_run(check, work, t0)
check.finish()
