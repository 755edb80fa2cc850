#!/usr/bin/env python3
"""The stepped workpiece (seed 000, experiments W1-W8 of Table 4.1) through the real CLI.

plan W8 in both dialects and W2 (fast transitions), W5 (continuous path) in LinuxCNC on the
3-axis VMC -> byte-identical re-plan -> the manifest (three programs, 21 features, the steps'
Temp state increasing, the same clock in both dialects) -> LinuxCNC's rs274 on the LinuxCNC
programs of W8, W2 and W5, checked against the manifest by check_sw_rs274.py (geometry of the
cuts and probe moves, and the programs re-timed from the canonical calls with the simulator's
clock: durations, cut and step times, Temp state, warm-up dwells, machine-off waits) -> W8
simulated on the virtual VMC (CMM export, probe log) -> bad inputs: refused with the key and
the value named, nothing written.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR; rs274 from scripts/setup.sh.
"""
import json, os, re, shutil, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-swcli-")
PIECE = f"{SRC}/parts/stepped_workpiece.yaml"
VMC = f"{SRC}/parts/machines/vmc3.yaml"
TEXT = open(PIECE).read()
check = Checks()


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def plan(name, experiment, dialect, piece=PIECE):
    out = f"{W}/{name}"
    code, o, e = run("plan", piece, "--machine", VMC, "--out", out, "--experiment", experiment, "--dialect", dialect)
    return code, o, e, out


def same_files(a, b):
    fa, fb = sorted(os.listdir(a)), sorted(os.listdir(b))
    return fa == fb and all(open(f"{a}/{f}", "rb").read() == open(f"{b}/{f}", "rb").read() for f in fa), fa


# --- plan: W8 in both dialects, W2 and W5 in LinuxCNC -----------------------------------------
dirs = {}
for name, exp, dialect in (("w8_lc", "W8", "linuxcnc"), ("w8_fa", "W8", "fanuc"), ("w2_lc", "W2", "linuxcnc"),
                           ("w5_lc", "W5", "linuxcnc")):
    code, out, err, d = plan(name, exp, dialect)
    check(f"plan {exp} ({dialect}, vmc3)", code == 0, err)
    if name == "w8_lc":
        print("\n".join("     " + l for l in out.splitlines()[:14]))
    dirs[name] = d
# W5 (one continuous contour) compensated with unequal offsets per wall and floor: the corners
# of the shifted contour and the raised/lowered floors go through rs274 below like the rest.
COMP = {"format": "probeloop-compensation", "kind": "stepped_workpiece", "experiment": "W5",
        "steps": [{"step": k, "wall_um": {"XP": 3.0 * k, "XN": -1.5 * k, "YP": 5.0 * k, "YN": 2.5},
                   "floor_um": -4.0 * k + 2} for k in range(1, 5)]}
open(f"{W}/w5_comp.json", "w").write(json.dumps(COMP))
code, out, err = run("plan", PIECE, "--machine", VMC, "--out", f"{W}/w5c_lc", "--experiment", "W5", "--compensate", f"{W}/w5_comp.json")
check("plan W5 --compensate (continuous path, unequal offsets)", code == 0, err)
dirs["w5c_lc"] = f"{W}/w5c_lc"
code, out, err = run("plan", PIECE, "--machine", VMC, "--out", f"{W}/bad_comp", "--experiment", "W8", "--compensate", f"{W}/w5_comp.json")
check("a compensation for W5 is refused when W8 is planned", code != 0 and "experiment: 'W5', but W8 is planned" in err
      and not os.path.exists(f"{W}/bad_comp"), err)
for name, ext in (("w8_lc", "ngc"), ("w8_fa", "nc")):
    want = sorted([f"roughing.{ext}", f"finishing.{ext}", f"probing.{ext}", "cmm_points.csv", "cmm_plan.qif", "cmm_plan.dmi", "plan.json"])
    got = sorted(os.listdir(dirs[name])) if os.path.isdir(dirs[name]) else []
    check(f"{name}: writes the three .{ext} programs, cmm_points.csv, cmm_plan.qif, cmm_plan.dmi and plan.json", got == want, got)
fa_text = open(f"{dirs['w8_fa']}/roughing.nc").read() if os.path.exists(f"{dirs['w8_fa']}/roughing.nc") else ""
check("Fanuc programs are numbered O3001..O3003", all(
    re.search(rf"^O{n}\b", open(f"{dirs['w8_fa']}/{f}.nc").read(), re.M)
    for n, f in ((3001, "roughing"), (3002, "finishing"), (3003, "probing"))) if fa_text else False)
for name, exp, dialect in (("w8_lc", "W8", "linuxcnc"), ("w8_fa", "W8", "fanuc")):
    code, _, err, d = plan(name + "_again", exp, dialect)
    ok, files = same_files(dirs[name], d) if code == 0 else (False, err)
    check(f"re-plan of {exp} ({dialect}) is byte-identical", ok, files)

# --- the manifest ------------------------------------------------------------------------------
man = {n: json.load(open(f"{d}/plan.json")) for n, d in dirs.items() if os.path.exists(f"{d}/plan.json")}
sides = ("XP", "XN", "YP", "YN", "F")
want_ids = {"TOP"} | {f"S{k}_{s}" for k in range(1, 5) for s in sides}
for n, m in sorted(man.items()):
    roles = [p["role"] for p in m["programs"]]
    ids = [f["id"] for f in m["features"]]
    steps = m["stepped_workpiece"]["steps"]
    temps = [s["temp_state_min"] for s in steps]
    check(f"{n}: kind stepped_workpiece, programs roughing, finishing, probing; 21 features (TOP + 4 x XP/XN/YP/YN/F)",
          m["kind"] == "stepped_workpiece" and roles == ["roughing", "finishing", "probing"] and len(ids) == 21 and
          set(ids) == want_ids, (m["kind"], roles, ids))
    check(f"{n}: experiment {m['stepped_workpiece']['experiment']}, 4 steps with Temp state increasing {[round(t, 2) for t in temps]} min",
          len(steps) == 4 and temps[0] > 0 and all(b > a for a, b in zip(temps, temps[1:])) and
          all(s["start_s"] < s["end_s"] for s in steps), steps)
if "w8_lc" in man and "w8_fa" in man:
    a, b = man["w8_lc"], man["w8_fa"]
    check("W8: the same clock in both dialects (programs, steps, cuts)",
          [(p["start_s"], p["duration_s"]) for p in a["programs"]] == [(p["start_s"], p["duration_s"]) for p in b["programs"]]
          and a["stepped_workpiece"]["steps"] == b["stepped_workpiece"]["steps"] and a["cuts"] == b["cuts"])
if "w2_lc" in man and "w5_lc" in man:
    check("W2 and W5 cut the alternative sizes 29/44/79/99 mm, W8 the standard 30/45/80/99 mm",
          man["w2_lc"]["stepped_workpiece"]["sizes_mm"] == [29, 44, 79, 99] == man["w5_lc"]["stepped_workpiece"]["sizes_mm"]
          and man.get("w8_lc", {}).get("stepped_workpiece", {}).get("sizes_mm") == [30, 45, 80, 99])
    check("transitions: W8 non_cutting, W2 fast, W5 continuous",
          [man[n]["stepped_workpiece"]["transition"] for n in ("w8_lc", "w2_lc", "w5_lc")] == ["non_cutting", "fast", "continuous"])

# --- LinuxCNC's rs274 on the LinuxCNC programs -------------------------------------------------
if shutil.which("rs274"):
    # Standalone rs274 reads tool lengths in inches (docs/sphere-cycle.md): the description's
    # tools and the machine's probe.
    table = []
    for n, body in re.findall(r"\{number: (\d+),(.*?)\}", TEXT, re.S):
        ln = float(re.search(r"[ ,]length: ([\d.]+) mm", body).group(1))
        table.append(f"T{n} P{n} Z{ln / 25.4:.9f} ;tool {n}")
    vmc = open(VMC).read()
    probe = re.search(r"^probe:\s*\n\s+tool: (\d+)\s*\n\s+length: ([\d.]+) mm", vmc, re.M)
    table.append(f"T{probe.group(1)} P{probe.group(1)} Z{float(probe.group(2)) / 25.4:.9f} ;probe")
    open(f"{W}/tool.tbl", "w").write("\n".join(table) + "\n")
    # The description's probing distances, not the program's own (a program consistently
    # wrong would otherwise pass).
    probing = TEXT[TEXT.index("\nprobing:"):]
    approach = re.search(r"\n\s+approach: ([\d.]+) mm", probing).group(1)
    overtravel = re.search(r"\n\s+overtravel: ([\d.]+) mm", probing).group(1)
    for name in ("w8_lc", "w2_lc", "w5_lc", "w5c_lc"):
        d = dirs[name]
        if name not in man:
            continue
        canons = []
        for p in man[name]["programs"]:
            c = subprocess.run(["rs274", "-t", f"{W}/tool.tbl", "-g", p["file"]], cwd=d, capture_output=True, text=True)
            open(f"{d}/{p['file']}.canon", "w").write(c.stdout + c.stderr)
            canons.append(f"{d}/{p['file']}.canon")
        p = subprocess.run([sys.executable, f"{SRC}/tests/integration/check_sw_rs274.py", f"{d}/plan.json", *canons,
                            "--approach", approach, "--overtravel", overtravel, "--machine", VMC, "--part", PIECE,
                            *(["--compensation", f"{W}/w5_comp.json"] if name == "w5c_lc" else [])],
                           capture_output=True, text=True)
        exp = man[name]["stepped_workpiece"]["experiment"] + (" (compensated)" if name == "w5c_lc" else "")
        check(f"rs274 accepts the three {exp} programs; cuts, probe moves and the manifest's times agree with "
              f"rs274's re-timed canonical calls", p.returncode == 0, p.stdout + p.stderr)
        print("\n".join("     " + l for l in p.stdout.splitlines()[-3:]))
else:
    check("rs274 installed (scripts/setup.sh)", False)

# --- W8 on the virtual VMC: machined, probed on the machine, measured on the CMM -------------------
# examples/truth_machining.yaml: a spindle that grows as it warms (tool_Z_um_per_K 4), a
# compliant structure, geometric errors of um/m. What must come out: every planned CMM point
# measured (141) and every probe point logged (165); the walls within 10 um of their nominal
# faces (the injected errors are a few um over these lengths); and the floors, each cut later
# in the run by a warmer spindle, displaced monotonically from step 1 to step 4 (the thermal
# stage signature the thesis's e_splz measures, notes §4.4).
w8 = dirs["w8_lc"]
code, out, err = run("simulate", f"{w8}/roughing.ngc", f"{w8}/finishing.ngc", f"{w8}/probing.ngc", "--machine", VMC,
                     "--part", PIECE, "--truth", f"{SRC}/examples/truth_machining.yaml",
                     "--cmm-points", f"{w8}/cmm_points.csv", "--out", f"{W}/run")
check("simulate W8: roughing, finishing and probing on the virtual VMC, then the CMM", code == 0, err)
print("     " + out.strip().replace("\n", "\n     "))
def rows(path):
    return [l.split(",") for l in open(path).read().splitlines() if l and not l.startswith("#")][1:] if os.path.exists(path) else []
planned, measured = rows(f"{w8}/cmm_points.csv"), rows(f"{W}/run/cmm_export.csv")
check("the CMM measures the 141 planned points, in the plan's order", len(measured) == 141 and
      [r[:2] for r in measured] == [r[:2] for r in planned], (len(planned), len(measured)))
log = open(f"{W}/run/sw_probe.log").read() if os.path.exists(f"{W}/run/sw_probe.log") else ""
check("the probing program logs its 165 points", len(re.findall(r"^PT ", log, re.M)) == 165, len(log))
dev = {}
for p, m in zip(planned, measured):
    P, M, N = [float(v) for v in p[2:5]], [float(v) for v in m[2:5]], [float(v) for v in p[5:8]]
    dev.setdefault(p[0], []).append(1e3 * sum((M[i] - P[i]) * N[i] for i in range(3)))
walls = [v for k, vs in dev.items() if k[-1] != "F" and k != "TOP" for v in vs]
check("every wall point lies within 10 um of its nominal face", walls and max(abs(v) for v in walls) < 10,
      f"max {max((abs(v) for v in walls), default=0):.2f} um")
floors = [sum(dev.get(f"S{k}_F", [0])) / max(1, len(dev.get(f"S{k}_F", []))) for k in range(1, 5)]
steps = [b - a for a, b in zip(floors, floors[1:])]
check("the floors move one way from step 1 to step 4 (the spindle warms through the run)",
      all(d > 0 for d in steps) or all(d < 0 for d in steps), " ".join(f"{v:.2f}" for v in floors) + " um")
print("     floor mean deviation per step (um): " + " ".join(f"{v:.2f}" for v in floors) +
      f"; walls within {max((abs(v) for v in walls), default=0):.2f} um")

# --- bad inputs: refused, the key and the value named, nothing written --------------------------
n_bad = 0


def variant(old, new, after=None):
    """The shipped description with `old` replaced by `new` (in the part after `after` only)."""
    global n_bad
    n_bad += 1
    head, tail = (TEXT.split(after, 1) if after else ("", TEXT))
    assert old in tail, old
    path = f"{W}/bad{n_bad}.yaml"
    open(path, "w").write(head + (after or "") + tail.replace(old, new, 1))
    return path


def refuses(name, piece, words, *extra):
    global n_bad
    n_bad += 1
    out = f"{W}/never{n_bad}"
    os.makedirs(out)  # a fresh, empty folder: nothing may be written into it
    code, o, e = run("plan", piece, "--machine", VMC, "--out", out, *extra)
    msg = o + e
    check(name, code != 0 and all(w in msg for w in words) and not os.listdir(out),
          f"exit {code}, wrote {os.listdir(out)}, message: {msg.strip()[:600]}")


refuses("W8 step 4 at feed_xy 20000 mm/min on a machine of 10000 is refused, naming feed_xy and 20000",
        variant("{feed_xy: 800, feed_z: 800, spindle_speed: 3500}", "{feed_xy: 20000, feed_z: 800, spindle_speed: 3500}",
                after="  - id: W8\n"), ["feed_xy", "20000"], "--experiment", "W8")
# vmc3: Z 150..550 mm, the clearance plane at tip Z 85, the deepest floor at tip Z 37.5. A
# 400 mm tool fits (gauge line 485 .. 437.5); 500 mm does not reach up (585 > 550), 100 mm
# not down (137.5 < 150).
refuses("a 500 mm tool (gauge line above the Z travel at the clearance plane) is refused, naming length and 500",
        variant("length: 140 mm", "length: 500 mm"), ["length", "500"], "--experiment", "W8")
refuses("a 100 mm tool (cannot reach the deepest floor within the Z travel) is refused, naming length and 100",
        variant("length: 140 mm", "length: 100 mm"), ["length", "100"], "--experiment", "W8")
refuses("a step 4 of 160 mm on the 150 mm blank is refused, naming steps and 160",
        variant("{size: 99 mm, floor_depth: 37 mm}", "{size: 160 mm, floor_depth: 37 mm}"), ["steps", "160"],
        "--experiment", "W8")
refuses("probe points below a wall's bottom edge (wall_levels [0.2, 1.3]) are refused, naming probing.wall_levels",
        variant("wall_levels: [0.2, 0.8]", "wall_levels: [0.2, 1.3]"), ["wall_levels"], "--experiment", "W8")
refuses("probe points off a wall's end (wall_positions [-0.6, 0, 1.2]) are refused, naming probing.wall_positions",
        variant("wall_positions: [-0.6, 0, 0.6]", "wall_positions: [-0.6, 0, 1.2]"), ["wall_positions"], "--experiment", "W8")
refuses("no --experiment: refused, the message lists W1 ... W8", PIECE, [f"W{k}" for k in range(1, 9)] + ["--experiment"])
refuses("--experiment W9: refused, naming W9 and the experiments there are", PIECE,
        ["W9"] + [f"W{k}" for k in range(1, 9)], "--experiment", "W9")

# A compensation that moves a floor up by more than the finishing margin roughing leaves.
thin = variant("finishing_margin: 0.5 mm", "finishing_margin: 0.2 mm")
raised = dict(COMP, experiment="W8", steps=[dict(st, wall_um={"XP": 0, "XN": 0, "YP": 0, "YN": 0}, floor_um=(300.0 if st["step"] == 2 else 0.0))
                                              for st in COMP["steps"]])
open(f"{W}/raised.json", "w").write(json.dumps(raised))
refuses("a floor raised beyond the finishing margin is refused (the key and the value)", thin,
        ["raised.json", "steps[1].floor_um: 300 um raises the floor by more than the finishing margin (200 um)"],
        "--experiment", "W8", "--compensate", f"{W}/raised.json")


shutil.rmtree(W, ignore_errors=True) if check.failed == 0 else print(f"     (outputs kept in {W})")
check.finish()
