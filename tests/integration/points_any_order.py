#!/usr/bin/env python3
"""Probe data from any cycle (issue 15 item 4): a sphere-artifact campaign's points.csv, written
again as another probing cycle and a European spreadsheet would (the points shuffled within each
position, foreign labels, no point numbers, a UTF-8 byte-order mark, CRLF, ';' separators,
decimal commas), evaluates to the same errors.csv as the original, to the printed digit.
Also: the Fanuc DPRNT log's clock (#3011/#3012) stamps each cycle within 1 s of the simulated
triggers; the plan's schedule (cycle starts + times in the cycle) within 1 s of the simulated clock
over the campaign; a user's file of cycle start times (--cycle-starts) stamps points without times; one point fewer per position still evaluates (n >= 4 with a known radius); a point moved
off its sphere, a comma-separated file with decimal commas and a C angle not planned are refused
naming file and line, and nothing is written.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import csv, io, os, random, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-anyorder-")
check = Checks()


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


code, _, err = run("plan", f"{SRC}/parts/sphere_artifact.yaml", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--out", f"{W}/plan")
check("plan", code == 0, err)
code, _, err = run("simulate", f"{W}/plan/sphere_cycle.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--part",
                   f"{SRC}/parts/sphere_artifact.yaml", "--truth", f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "3")
check("simulate", code == 0, err)
lines = [l for l in open(f"{W}/run/points.csv") if not l.startswith("#")]
rows = list(csv.DictReader(lines))
header = list(rows[0].keys())


# The plan's schedule against the simulated clock: every point's planned time (its cycle's start
# + its time in the cycle) within 1 s of when the simulator's probe triggered, over all cycles
# (the C return and the tool changes in the schedule; what remains is the probing moves meeting
# the sphere where the errors put it).
import json  # noqa: E402
plan = json.load(open(f"{W}/plan/plan.json"))
planned = {(p["feature"], p["point"]): p["time_in_cycle_s"] for p in plan["points"]}
starts = plan["schedule"]["cycle_start_s"]
drift = max(abs(float(r["time_s"]) - (starts[int(r["cycle"]) - 1] + planned[(r["feature"], int(r["point"]))])) for r in rows)
check(f"the schedule follows the simulated clock: worst |planned - simulated| {drift:.3f} s over {len(starts)} cycles", drift < 1.0)


def evaluate(points, out):
    return run("evaluate", points, "--format", "csv", "--manifest", f"{W}/plan/plan.json", "--out", out)


def numbers(errors_csv):
    return [l for l in open(errors_csv) if not l.startswith("#")]


code, _, err = evaluate(f"{W}/run/points.csv", f"{W}/ev0")
check("evaluate the points as simulated", code == 0, err)

# The same points as another cycle writes them.
rng = random.Random(7)
groups = {}
for r in rows:
    groups.setdefault((r["cycle"], r["feature"]), []).append(r)
foreign = {f: f"Kugel {i}" for i, f in enumerate(sorted({r["feature"] for r in rows}), start=1)}
cols = ["cycle", "c_deg", "feature", "time_s", "x_mm", "y_mm", "z_mm"]


def european(rows_out):
    text = "\ufeff" + ";".join(cols) + "\r\n"
    for r in rows_out:
        text += ";".join(r[c].replace(".", ",") if c != "feature" else foreign[r[c]] for c in cols) + "\r\n"
    return text


shuffled = []
for key in sorted(groups, key=lambda k: (int(k[0]), k[1]), reverse=True):  # positions in another order too
    g = groups[key][:]
    rng.shuffle(g)
    shuffled += g
with open(f"{W}/eu.csv", "w", encoding="utf-8", newline="") as f:
    f.write(european(shuffled))
code, out, err = evaluate(f"{W}/eu.csv", f"{W}/ev1")
check("the shuffled, relabelled, CRLF, ';' + decimal-comma file evaluates", code == 0, err)
if code == 0:
    a, b = numbers(f"{W}/ev0/errors.csv"), numbers(f"{W}/ev1/errors.csv")
    check(f"... to the same errors.csv, every printed digit ({len(a) - 1} cycles)", a == b,
          next((f"{x.strip()} | {y.strip()}" for x, y in zip(a, b) if x != y), "row count"))

# The Fanuc log carries the controller's clock (#3011/#3012 with every point, START when the
# program starts): evaluated from dprnt.txt, each cycle's time agrees with the one from the
# simulator's own trigger times within 1 s.
code, _, err = run("evaluate", f"{W}/run/dprnt.txt", "--format", "fanuc", "--manifest", f"{W}/plan/plan.json", "--out", f"{W}/ev-dprnt")
check("evaluate the DPRNT log", code == 0, err)
if code == 0:
    t_log = [float(l.split(",")[0]) for l in numbers(f"{W}/ev-dprnt/errors.csv")[1:]]
    t_sim = [float(l.split(",")[0]) for l in numbers(f"{W}/ev0/errors.csv")[1:]]
    worst = max(abs(a - b) for a, b in zip(t_log, t_sim))
    check(f"the DPRNT clock stamps each cycle within 1 s of the simulated triggers (worst {worst:.3f} s over {len(t_log)} cycles)",
          len(t_log) == len(t_sim) and worst < 1.0)

# Without times, the planned schedule stamps the points (each paired with its nearest planned
# contact): the shuffled file and the original, both without time_s, agree.
def without_time(rows_in, sep=","):
    cs = [c for c in cols if c != "time_s"]
    return sep.join(cs) + "\n" + "".join(sep.join(r[c] for c in cs) + "\n" for r in rows_in)


orig_nt = [r for r in rows]
with open(f"{W}/nt0.csv", "w") as f:
    f.write(without_time(orig_nt).replace("feature", "feature", 1))
nt1 = [dict(r, feature=foreign[r["feature"]]) for r in shuffled]
with open(f"{W}/nt1.csv", "w") as f:
    f.write(without_time(nt1))
c0, _, e0 = evaluate(f"{W}/nt0.csv", f"{W}/ev-nt0")
c1, _, e1 = evaluate(f"{W}/nt1.csv", f"{W}/ev-nt1")
check("without time_s, shuffled and relabelled, the same errors.csv as the original without time_s",
      c0 == 0 and c1 == 0 and numbers(f"{W}/ev-nt0/errors.csv") == numbers(f"{W}/ev-nt1/errors.csv"), e0 + e1)

# A user's file of cycle start times (--cycle-starts) stamps a log without clocks: the starts read
# off the simulated triggers (each cycle's earliest trigger minus its planned time in the cycle)
# give each cycle's time within 1 s of the timed points'; the same starts 500 s later move every
# time by 500 s and change no error; a file that skips a cycle, or ends before the log does, is
# refused naming the line or the cycle, and nothing is written.
sim_start = {}
for r in rows:
    c = int(r["cycle"])
    s0 = float(r["time_s"]) - planned[(r["feature"], int(r["point"]))]
    sim_start[c] = min(sim_start.get(c, s0), s0)


def starts_file(name, shift=0.0, cycles=None, sep=","):
    path = f"{W}/{name}.csv"
    with open(path, "w") as f:
        f.write(f"cycle{sep}start_s\n" + "".join(f"{c}{sep}{sim_start[c] + shift:.3f}\n".replace(".", "," if sep == ";" else ".")
                                              for c in (cycles or sorted(sim_start))))
    return path


def evaluate_starts(starts, out):
    return run("evaluate", f"{W}/nt0.csv", "--format", "csv", "--manifest", f"{W}/plan/plan.json", "--cycle-starts", starts, "--out", out)


c0, _, e0 = evaluate_starts(starts_file("starts", sep=";"), f"{W}/ev-st0")
c1, _, e1 = evaluate_starts(starts_file("starts-late", 500.0), f"{W}/ev-st1")
check("--cycle-starts (';' and decimal commas) evaluates", c0 == 0 and c1 == 0, e0 + e1)
if c0 == 0 and c1 == 0:
    a, b, ref = (numbers(f"{W}/{d}/errors.csv")[1:] for d in ("ev-st0", "ev-st1", "ev0"))
    worst = max(abs(float(x.split(",")[0]) - float(y.split(",")[0])) for x, y in zip(a, ref))
    check(f"the user's cycle starts stamp each cycle within 1 s of the simulated triggers (worst {worst:.3f} s)",
          len(a) == len(ref) and worst < 1.0)
    shifted = all(abs(float(y.split(",")[0]) - float(x.split(",")[0]) - 500.0) < 1e-3 and x.split(",")[1:] == y.split(",")[1:]
                  for x, y in zip(a, b))
    check("starts 500 s later: every time 500 s later, every error the same", len(a) == len(b) and shifted)
n_cycles = len(sim_start)
for name, path, want in (("a skipped cycle", starts_file("starts-skip", cycles=[1, 3]), "starts-skip.csv:3: cycle: 3; expected 2"),
                         ("a file that ends early", starts_file("starts-short", cycles=list(range(1, n_cycles))),
                          f"cycle {n_cycles}: no start time"),
                         ("starts not increasing", f"{W}/starts-back.csv", "starts-back.csv:3: start_s: 5 is not after")):
    if name == "starts not increasing":
        open(path, "w").write("cycle,start_s\n1,10\n2,5\n")
    code, _, err = evaluate_starts(path, f"{W}/bad-starts")
    check(f"--cycle-starts with {name}: refused with '{want}', nothing written", code != 0 and want in err and not os.path.exists(f"{W}/bad-starts"), err)

# One point fewer per position: still a sphere with its known radius.
fewer = []
for key in sorted(groups):
    fewer += groups[key][1:]
with open(f"{W}/fewer.csv", "w", newline="") as f:
    f.write(",".join(cols) + "\n" + "".join(",".join(r[c] for c in cols) + "\n" for r in fewer))
code, out, err = evaluate(f"{W}/fewer.csv", f"{W}/ev2")
check("one point fewer per position evaluates", code == 0 and os.path.exists(f"{W}/ev2/errors.csv"), err)


def refused(name, text, want):
    path = f"{W}/{name}.csv"
    with open(path, "w", newline="") as f:
        f.write(text)
    code, _, err = evaluate(path, f"{W}/bad-{name}")
    check(f"{name}: refused with '{want}', nothing written", code != 0 and want in err and not os.path.exists(f"{W}/bad-{name}"), err)


off = [dict(r) for r in shuffled]
off[5]["x_mm"] = str(float(off[5]["x_mm"]) + 20.0)
refused("off-sphere", european(off), "off-sphere.csv:7: point is")
comma_text = ",".join(cols) + "\n" + "".join(",".join(r[c].replace(".", ",") if c != "feature" else r[c] for c in cols) + "\n" for r in rows)
refused("comma-decimal", comma_text, "comma-decimal.csv:2: expected 7 fields")
moved = [dict(r) for r in rows]
moved[3]["x_mm"] = str(float(moved[3]["x_mm"]) + 30.0)
refused("id-moved", ",".join(["cycle", "c_deg", "feature", "x_mm", "y_mm", "z_mm"]) + "\n" +
        "".join(",".join(r[c] for c in ["cycle", "c_deg", "feature", "x_mm", "y_mm", "z_mm"]) + "\n" for r in moved),
        "id-moved.csv:5: point is")
bad_c = [dict(r) for r in shuffled]
bad_c[0]["c_deg"] = "17"
refused("c-not-planned", european(bad_c), "c-not-planned.csv:2: c_deg 17 is not a planned C position")

# Repeats at one C angle (c_positions 0, 90, 180, 270, 0: positions 1 and 5 are the same sphere in
# the same place): foreign labels with times tell them apart, in any order; without labels the
# points are refused with the reason.
art = open(f"{SRC}/parts/sphere_artifact.yaml").read()
import re  # noqa: E402
art2 = re.sub(r"c_positions: \[[^]]*\]", "c_positions: [0, 90, 180, 270, 0]", art)
check("an artifact with a repeated C position", art2 != art)
with open(f"{W}/repeat.yaml", "w") as f:
    f.write(art2)
code, _, err = run("plan", f"{W}/repeat.yaml", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--out", f"{W}/rplan")
check("plan with a repeated C", code == 0, err)
code, _, err = run("simulate", f"{W}/rplan/sphere_cycle.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--part",
                   f"{W}/repeat.yaml", "--truth", f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/rrun", "--seed", "4")
check("simulate with a repeated C", code == 0, err)
if code == 0:
    rrows = list(csv.DictReader(l for l in open(f"{W}/rrun/points.csv") if not l.startswith("#")))
    code, _, err = run("evaluate", f"{W}/rrun/points.csv", "--format", "csv", "--manifest", f"{W}/rplan/plan.json", "--out", f"{W}/rev0")
    check("evaluate the repeated-C points as simulated", code == 0, err)
    rg = {}
    for r in rrows:
        rg.setdefault((r["cycle"], r["feature"]), []).append(r)
    rsh = []
    for key in sorted(rg, key=lambda k: (int(k[0]), k[1]), reverse=True):
        g = rg[key][:]
        rng.shuffle(g)
        rsh += g
    lab = {f: f"Q{9 - i}" for i, f in enumerate(sorted({r["feature"] for r in rrows}))}
    with open(f"{W}/rep.csv", "w") as f:
        f.write(",".join(cols) + "\n" + "".join(",".join(r[c] if c != "feature" else lab[r[c]] for c in cols) + "\n" for r in rsh))
    code, _, err = run("evaluate", f"{W}/rep.csv", "--format", "csv", "--manifest", f"{W}/rplan/plan.json", "--out", f"{W}/rev1")
    check("repeated C, shuffled, foreign labels with times: the same errors.csv",
          code == 0 and numbers(f"{W}/rev0/errors.csv") == numbers(f"{W}/rev1/errors.csv"), err)
    with open(f"{W}/rep-nolabel.csv", "w") as f:
        cs = ["cycle", "c_deg", "time_s", "x_mm", "y_mm", "z_mm"]
        f.write(",".join(cs) + "\n" + "".join(",".join(r[c] for c in cs) + "\n" for r in rrows))
    code, _, err = run("evaluate", f"{W}/rep-nolabel.csv", "--format", "csv", "--manifest", f"{W}/rplan/plan.json", "--out", f"{W}/rev2")
    check("repeated C without labels: refused with the reason", code != 0 and "holds positions 1, 5" in err and not os.path.exists(f"{W}/rev2"), err)
check.finish()
