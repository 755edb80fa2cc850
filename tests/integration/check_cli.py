#!/usr/bin/env python3
"""The safety verifier (`probeloop check`, docs/reliability.md#safety-verifier) through the real CLI.

1. Every program `plan` emits for the shipped parts (sphere artifact, thermal test piece,
   stepped workpiece W1-W8) on the shipped machines, in both dialects, passes `check`
   (exit 0, no finding), the programs of a plan checked back to back as they run. Under the
   sanitizers (CHECK_QUICK=1: each plan there takes seconds, not tenths) the stepped
   workpiece is planned for W2 and W8 only (its transitions part and the reference part);
   the release build plans all of W1-W8.
2. Programs `plan` really emitted, edited to be unsafe: each caught with its rule at the
   edited line (exit 3), and nothing found that the edit does not explain: off travel, a
   rapid through the sphere, a rapid through the stock, a protected move's check removed
   (LinuxCNC) and a measuring move's check removed (Fanuc), an unprotected descent beside the
   sphere, C indexed below the clearance plane, the spindle started with the probe.
3. `plan` refuses a plan the verifier finds unsafe (a probe with a 5 mm stylus: its body
   meets the sphere), exit 3, the finding on stderr, nothing written.
4. `--json`; bad input is exit 2 with file:line.

The edits of sections 2 and 5 are in unsafe_edits.py (shared with linuxcnc_safety.py, which runs the
LinuxCNC ones on LinuxCNC in simulation).

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR.
"""
import json, os, re, shutil, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from unsafe_edits import (first, off_travel, rapid_through_sphere, no_contact_check, no_trigger_check,  # noqa: E402
                          unprotected_descent, c_below_clearance, spindle_with_probe, rapid_through_stock,
                          NONFINITE, insert_after, rapid_only)

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-check-")
MACHINES = {m: f"{SRC}/parts/machines/{m}.yaml" for m in ("nmv5000", "linuxcnc_rotary_mill", "vmc3", "gantry_seed003")}
PIECES = {"sphere": f"{SRC}/parts/sphere_artifact.yaml", "ttp": f"{SRC}/parts/thermal_test_piece.yaml",
          "sw": f"{SRC}/parts/stepped_workpiece.yaml"}
check = Checks()
t0 = time.time()


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def programs_of(out):
    """The programs of a plan in the order they run (plan.json)."""
    m = json.load(open(f"{out}/plan.json"))
    return [f"{out}/{p['file']}" for p in m["programs"]]


def findings(stdout):
    """(rule, line) of each finding line 'file:line: rule: ...'."""
    return [(m.group(2), int(m.group(1))) for m in re.finditer(r"^\S+?:(\d+): ([a-z-]+): ", stdout, re.M)]


# --- 1. every shipped plan passes ---------------------------------------------------------------
plans = []
for machine in ("nmv5000", "linuxcnc_rotary_mill"):
    for dialect in ("linuxcnc", "fanuc"):
        plans.append(("sphere", machine, dialect, None))
        plans.append(("ttp", machine, dialect, None))
for machine in ("vmc3", "nmv5000", "linuxcnc_rotary_mill"):
    for dialect in ("linuxcnc", "fanuc"):
        for k in ((2, 8) if os.environ.get("CHECK_QUICK") == "1" else range(1, 9)):
            plans.append(("sw", machine, dialect, f"W{k}"))
# seed 003's gantry (X, Y, Z all on the tool side): the stepped workpiece's first and last experiments
for dialect in ("linuxcnc", "fanuc"):
    for k in (2, 8):
        plans.append(("sw", "gantry_seed003", dialect, f"W{k}"))
dirs = {}
for piece, machine, dialect, exp in plans:
    out = f"{W}/{piece}_{machine}_{dialect}" + (f"_{exp}" if exp else "")
    args = ["plan", PIECES[piece], "--machine", MACHINES[machine], "--dialect", dialect, "--out", out]
    if exp:
        args += ["--experiment", exp]
    code, o, e = run(*args)
    name = f"{piece} {exp or ''} on {machine} ({dialect})"
    if code != 0:
        check(f"plan {name}", False, e)
        continue
    progs = programs_of(out)
    dirs[(piece, machine, dialect, exp)] = out
    if piece == "sw" and exp != "W8":
        check(f"plan {name}: its own verifier passed {len(progs)} program(s)", True)
        continue  # plan ran the verifier (exit 0); `check` again on W8 of each machine and dialect
    code, o, e = run("check", *progs, "--machine", MACHINES[machine], "--part", PIECES[piece])
    check(f"check {name}: {len(progs)} program(s) safe", code == 0 and o.startswith("safe: 0 finding(s)"), o + e)
print(f"     {len(dirs)} plans, {sum(len(programs_of(d)) for d in dirs.values())} programs checked "
      f"({time.time() - t0:.1f} s)")


# --- 2. unsafe edits of emitted programs ----------------------------------------------------------
def edited(src, name, edit):
    lines = open(src).read().split("\n")
    lines, expect, allowed = edit(lines)
    path = f"{W}/{name}" + os.path.splitext(src)[1]
    open(path, "w").write("\n".join(lines))
    return path, expect, allowed


sphere_lc = dirs[("sphere", "linuxcnc_rotary_mill", "linuxcnc", None)]
sphere_fa = dirs[("sphere", "nmv5000", "fanuc", None)]
sw_fa = dirs[("sw", "vmc3", "fanuc", "W8")]
cases = [
    ("off_travel", f"{sphere_lc}/sphere_cycle.ngc", off_travel, "linuxcnc_rotary_mill", "sphere"),
    ("rapid_through_sphere", f"{sphere_lc}/sphere_cycle.ngc", rapid_through_sphere, "linuxcnc_rotary_mill", "sphere"),
    ("rapid_through_sphere_fanuc", f"{sphere_fa}/sphere_cycle.nc", rapid_through_sphere, "nmv5000", "sphere"),
    ("no_contact_check", f"{sphere_lc}/sphere_cycle.ngc", no_contact_check, "linuxcnc_rotary_mill", "sphere"),
    ("no_trigger_check_fanuc", f"{sphere_fa}/sphere_cycle.nc", no_trigger_check, "nmv5000", "sphere"),
    ("unprotected_descent", f"{sphere_lc}/sphere_cycle.ngc", unprotected_descent, "linuxcnc_rotary_mill", "sphere"),
    ("c_below_clearance", f"{sphere_lc}/sphere_cycle.ngc", c_below_clearance, "linuxcnc_rotary_mill", "sphere"),
    ("spindle_with_probe", f"{sphere_fa}/sphere_cycle.nc", spindle_with_probe, "nmv5000", "sphere"),
]
for name, src, edit, machine, piece in cases:
    path, expect, allowed = edited(src, name, edit)
    code, o, e = run("check", path, "--machine", MACHINES[machine], "--part", PIECES[piece])
    got = findings(o)
    check(f"{name}: {expect[0]} at line {expect[1]} (exit 3)", code == 3 and expect in got, o + e)
    check(f"{name}: nothing else found", set(got) <= {expect} | allowed, o)
# The stock: the roughing program edited, checked with the programs after it (as they run).
rough = [p for p in programs_of(sw_fa) if "roughing" in p][0]
path, expect, allowed = edited(rough, "roughing_through_stock", rapid_through_stock)
rest = [p for p in programs_of(sw_fa) if p != rough]
code, o, e = run("check", path, *rest, "--machine", MACHINES["vmc3"], "--part", PIECES["sw"])
got = findings(o)
check(f"rapid_through_stock: collision with the stock at line {expect[1]} (exit 3)",
      code == 3 and expect in got and "meets the stock" in o, o + e)
check("rapid_through_stock: nothing else found", set(got) <= {expect} | allowed, o)
# The same rapid before any cut would be clear of the (uncut) level 1: the material model carries the cuts.
code, o, e = run("check", *programs_of(sw_fa), "--machine", MACHINES["vmc3"], "--part", PIECES["sw"])
check("the unedited roughing, finishing and probing of W8 (Fanuc) stay safe", code == 0, o + e)

# --- 3. plan refuses what the verifier finds --------------------------------------------------------
short = open(MACHINES["linuxcnc_rotary_mill"]).read().replace(
    "  tip_diameter: 6 mm\n", "  tip_diameter: 6 mm\n  stylus_length: 5 mm   # a short stylus: the body comes down to the sphere\n")
assert "stylus_length" in short
open(f"{W}/short_stylus.yaml", "w").write(short)
code, o, e = run("plan", PIECES["sphere"], "--machine", f"{W}/short_stylus.yaml", "--out", f"{W}/refused")
check("plan with a 5 mm stylus: refused (exit 3) naming the probe body and the sphere",
      code == 3 and "plan refused" in e and "collision" in e and "probe body" in e, (code, e[:600]))
check("plan refused: nothing written", not os.path.exists(f"{W}/refused") or not os.listdir(f"{W}/refused"),
      os.listdir(f"{W}/refused") if os.path.exists(f"{W}/refused") else "")

# --- 4. JSON and bad input -------------------------------------------------------------------------
path, expect, _ = edited(f"{sphere_lc}/sphere_cycle.ngc", "json_case", off_travel)
code, o, e = run("check", path, "--machine", MACHINES["linuxcnc_rotary_mill"], "--part", PIECES["sphere"], "--json")
try:
    j = json.loads(o)
    ok = (code == 3 and j["safe"] is False and j["findings"][0]["rule"] == "travel" and j["findings"][0]["line"] == expect[1]
          and len(j["findings"][0]["where_mm"]) == 3 and "stylus shaft" in j["model"])
except (ValueError, KeyError, IndexError) as ex:
    ok, o = False, f"{ex}: {o[:400]}"
check("--json: safe false, the travel finding with its line, where_mm and the model", ok, o[:600])
bad = open(MACHINES["nmv5000"]).read().replace("  tip_diameter: 6 mm", "  tip_diameter: 6 mm\n  stylus_lenght: 40 mm")
open(f"{W}/bad_machine.yaml", "w").write(bad)
code, o, e = run("check", f"{sphere_fa}/sphere_cycle.nc", "--machine", f"{W}/bad_machine.yaml", "--part", PIECES["sphere"])
check("unknown machine key: exit 2 naming file:line and the key", code == 2 and re.search(r"bad_machine\.yaml:\d+", e)
      and "stylus_lenght" in e, e)
lines = open(f"{sphere_lc}/sphere_cycle.ngc").read().split("\n")
i = first(lines, r"G43 H99")
lines.insert(i + 1, "G0 X0 Q5")
open(f"{W}/bad_word.ngc", "w").write("\n".join(lines))
code, o, e = run("check", f"{W}/bad_word.ngc", "--machine", MACHINES["linuxcnc_rotary_mill"], "--part", PIECES["sphere"])
check("a word the interpreter does not model: exit 2 with file:line", code == 2 and f"bad_word.ngc:{i + 2}:" in e, e)
# --- 5. programs that compute a coordinate that is not a number (issue 28) -------------------------
# Before: an overflow to infinity, inf - inf = NaN, a move to it, then an ordinary rapid into the
# stock passed as "safe: 0 findings" (a NaN compares false with every limit). Now the program
# cannot be evaluated: exit 2 naming the line and the expression, never "safe".
# The programs: unsafe_edits.NONFINITE (shared with linuxcnc_safety.py).
nonfinite = [(name, f"{sphere_lc}/sphere_cycle.ngc" if dialect == "linuxcnc" else f"{sphere_fa}/sphere_cycle.nc",
              after, insert, bad, text) for name, dialect, after, insert, bad, text in NONFINITE]
for name, src, after, insert, bad, text in nonfinite:
    lines, i = insert_after(open(src).read().split("\n"), after, insert)
    path = f"{W}/{name}" + os.path.splitext(src)[1]
    open(path, "w").write("\n".join(lines))
    machine = "linuxcnc_rotary_mill" if src.endswith(".ngc") else "nmv5000"
    code, o, e = run("check", path, "--machine", MACHINES[machine], "--part", PIECES["sphere"])
    check(f"{name}: exit 2 at line {i + 1 + bad} ({text.strip()}), not 'safe'",
          code == 2 and f"{os.path.basename(path)}:{i + 1 + bad}: {text}" in e and "not a finite number" in e
          and "safe" not in o, (code, o[:300], e[:600]))
# The same rapid into the sphere without the NaN move before it is a collision (exit 3): the NaN
# used to hide it.
lines, i = rapid_only(open(f"{sphere_lc}/sphere_cycle.ngc").read().split("\n"))
open(f"{W}/rapid_only.ngc", "w").write("\n".join(lines))
code, o, e = run("check", f"{W}/rapid_only.ngc", "--machine", MACHINES["linuxcnc_rotary_mill"], "--part", PIECES["sphere"])
check("the rapid alone: a finding (exit 3)", code == 3 and "UNSAFE" in o, (code, o[:400]))
print(f"     {time.time() - t0:.1f} s")
if not check.failed:
    shutil.rmtree(W, ignore_errors=True)  # kept on failure, for a look at the edited programs
check.finish()
