#!/usr/bin/env python3
"""The generalised sphere cycle (issue 33: tilted positions) through LinuxCNC's own rs274.

`probeloop plan` plans examples/rotary/sphere_artifact_bc.yaml (four level C positions and six
tilted ones, B +-30 deg) on the LinuxCNC B/C trunnion mill and on the NMV 5000 in the LinuxCNC
dialect, and the same positions with A instead of B on the table-table A/C machine. `plan`
checks every program with the safety verifier before writing it (its swing check included);
`probeloop check` passes them again. Then rs274 runs each program: it reaches PROGRAM_END
without an ABORT, makes two probe moves per planned point and cycle, each measuring move at
the manifest's contact + overtravel along the approach with A/B/C at the position's angles,
logs one PT line per point, and every move of A, B or C happens with the tip at or above the
clearance plane of the highest tilted sphere (the program goes up before the rotary axes move).
The trunnion's program edited to swing B over a lowered probe is refused by `check` at the B
line. About 5 s.

Needs $PROBELOOP, $PROBELOOP_SOURCE_DIR and rs274 (scripts/setup.sh installs it).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
ART_BC = f"{SRC}/examples/rotary/sphere_artifact_bc.yaml"
W = tempfile.mkdtemp(prefix="probeloop-tilt-rs274-")
check = Checks()
NUM = r"(-?\d+\.\d+)"


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def calls(text, name):
    return [[float(v) for v in m.split(",")] for m in re.findall(name + r"\(([-0-9., ]+)\)", text)]


def mm(q):
    return float(str(q).split()[0])


def rs274_check(label, folder, axis, art):
    """rs274 on folder/sphere_cycle.ngc against folder/plan.json and the artifact; axis 'A' or 'B'."""
    plan = json.load(open(f"{folder}/plan.json"))
    probing = yaml.safe_load(open(art))["probing"]
    overtravel, clearance = mm(probing["overtravel"]), mm(probing["clearance_above_sphere"])
    # rs274 standalone reads tool lengths in inches: the probe's 150 mm.
    open(f"{folder}/tool.tbl", "w").write("T99 P99 Z5.905511811 D0.236220472 ;probe\n")
    p = subprocess.run(["rs274", "-t", "tool.tbl", "-g", "sphere_cycle.ngc"], cwd=folder, capture_output=True, text=True)
    canon = p.stdout + p.stderr
    check(f"{label}: rs274 runs the program to PROGRAM_END without an ABORT",
          "PROGRAM_END" in canon and "ABORT" not in canon, canon[-1500:])
    points, cycles = plan["points"], plan["schedule"]["cycles"]
    features = {f["position"]: f for f in plan["features"]}
    tilted = [f for f in plan["features"] if f.get("tilt_deg", 0) != 0]
    check(f"{label}: the plan tilts {axis} at {len(tilted)} positions",
          len(tilted) == 6 and plan["machine"]["tilt_axis"]["name"] == axis, plan["machine"].get("tilt_axis"))
    probes = calls(canon, "STRAIGHT_PROBE")
    check(f"{label}: two probe moves per point and cycle ({2 * len(points) * cycles})",
          len(probes) == 2 * len(points) * cycles, len(probes))
    logs = re.findall(r'LOG\("PT ([^"]*)"\)', canon)
    check(f"{label}: one PT line per point and cycle", len(logs) == len(points) * cycles, len(logs))
    k_axis = 3 if axis == "A" else 4
    bad = []
    for i, p in enumerate(probes[1::2][:len(points)]):
        pt = points[i]
        want = [pt["contact_mm"][k] + overtravel * pt["approach"][k] for k in range(3)]
        f = features[pt["position"]]
        if max(abs(p[k] - want[k]) for k in range(3)) > 6e-5 or abs(p[k_axis] - f.get("tilt_deg", 0)) > 5e-4 \
                or abs(p[5] - f["c_deg"]) > 5e-4:
            bad.append((i, p[:6], want, f.get("tilt_deg", 0), f["c_deg"]))
    check(f"{label}: each measuring move at the planned contact + overtravel, {axis} and C at the position's angles",
          not bad, bad[:3])
    # C on the level table turns the sphere at its own height: the level clearance plane (seed
    # 004's cycle). A move that tilts, or turns C on the tilted table, goes above the highest
    # sphere of any position plus the clearance.
    r = plan["artifact"]["sphere_radius_mm"]
    level = plan["machine"]["table_surface_z_mm"] + plan["artifact"]["sphere_centre_height_mm"] + r + clearance
    tilted_plane = max(f["nominal_centre_mm"][2] for f in plan["features"]) + r + clearance
    tip_r = plan["probe"]["tip_radius_mm"]
    moves = calls(canon, "STRAIGHT_TRAVERSE")
    rotary, tilting, low = 0, 0, []
    for a, b in zip(moves, moves[1:]):
        if not any(abs(a[k] - b[k]) > 1e-9 for k in (3, 4, 5)):
            continue
        rotary += 1
        tilts = a[k_axis] != 0 or b[k_axis] != 0
        tilting += tilts
        plane = tilted_plane if tilts else level
        if min(a[2], b[2]) - tip_r < plane - 1e-4:
            low.append((a[:6], b[:6], plane))
    check(f"{label}: all {rotary} moves of A, B or C above the clearance plane ({tilting} on the tilted table above Z "
          f"{tilted_plane:.3f}, the highest sphere + clearance; the others above the level plane Z {level:.3f})",
          tilting >= 6 and not low, low[:3])


def swing_edit(folder, machine, art):
    """The retract before position 7's tilt (B +30 -> -30 at C 90) replaced by a move to X0 Y160,
    where the sphere's centre passes at B 0 (Z 75; at B = q it is at X -75 sin q, Z 75 cos q).
    With the tip at Z94 the swing brings the sphere within 2 mm of the tip (radii 15 + 3 plus the
    margin: 20 mm between centres) at cos q = 14061/14100, q = 4.26 deg: check refuses the B
    line with tilt-swing. With the tip at Z100 (7 mm clear at B 0) the B line passes."""
    lines = open(f"{folder}/sphere_cycle.ngc").read().split("\n")
    i = next(k for k, l in enumerate(lines) if l.startswith("(position 7 [B -30, C 90]"))
    assert lines[i + 1].startswith("G53 G0 Z") and lines[i + 2] == "G0 B-30.000", lines[i:i + 3]
    for z, refused in (("94", True), ("100", False)):
        lines[i + 1] = f"G0 X0.0000 Y160.0000 Z{z}.0000"
        path = f"{folder}/swing_edit.ngc"
        open(path, "w").write("\n".join(lines))
        code, out = run("check", path, "--machine", machine, "--part", art)
        at = f"swing_edit.ngc:{i + 3}: tilt-swing: "
        if refused:
            m = re.search(re.escape(at) + r"B moves from 30.000 to -30.000 deg: the table swings the sphere of the artifact "
                          r"within [0-9.]+ mm of the probe's stylus tip at B ([-0-9.]+) deg", out)
            check("an emitted program edited to swing B over a probe lowered to Z94: check refuses the B line "
                  "(tilt-swing at B 4.26 deg, derived)", code == 3 and m is not None and abs(float(m.group(1)) - 4.26) < 0.05,
                  out[-1500:])
        else:
            check("... with the probe at Z100 the B line passes", at not in out, out[-1500:])


try:
    machines = [("B/C trunnion (LinuxCNC)", f"{SRC}/parts/machines/linuxcnc_trunnion_bc.yaml", ART_BC, "B", []),
                ("NMV 5000 in the LinuxCNC dialect", f"{SRC}/parts/machines/nmv5000.yaml", ART_BC, "B",
                 ["--dialect", "linuxcnc"])]
    art_ac = f"{W}/sphere_artifact_ac.yaml"
    open(art_ac, "w").write(re.sub(r"\{B: ", "{A: ", open(ART_BC).read()))
    machines.append(("A/C table-table", f"{SRC}/parts/machines/table_table_ac.yaml", art_ac, "A", []))
    for n, (label, machine, art, axis, extra) in enumerate(machines):
        folder = f"{W}/p{n}"
        code, out = run("plan", art, "--machine", machine, "--out", folder, *extra)
        check(f"{label}: plan (its safety verifier included) accepts the tilted cycle", code == 0, out[-1500:])
        if code != 0:
            continue
        code, out = run("check", f"{folder}/sphere_cycle.ngc", "--machine", machine, "--part", art)
        check(f"{label}: probeloop check finds nothing", code == 0, out[-1500:])
        if n == 0:
            swing_edit(folder, machine, art)
        if shutil.which("rs274") is None:
            check("rs274 is installed (scripts/setup.sh)", False)
            continue
        rs274_check(label, folder, axis, art)
finally:
    shutil.rmtree(W, ignore_errors=True)
check.finish()
