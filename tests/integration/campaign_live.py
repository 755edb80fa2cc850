#!/usr/bin/env python3
"""The live TALC loop through the real CLI (issue 30 items 2 and 5): `campaign run` on a simulated
sphere campaign (Fanuc DPRNT log, the demo's truth with its door event).

- Replaying a densely measured log with --requested-only gives exactly what the offline replay
  `model talc` gives on the same store's exported CSVs and grid: the same measurements taken, the
  same Table 6.5 rows (an independent driver of the same TALC rules: the replay decides from the
  whole campaign at once, the live loop step by step as the data arrive);
- the log and the inputs written in pieces in time order (torn lines included), `campaign run`
  after each piece, SIGKILLed at random instants (at least 50 kills) and run again: the final
  store holds exactly what one uninterrupted run over the complete files stored, table by table
  (no cycle lost or fed twice, no prediction issued twice or out of order);
- the predictions are issued in grid order, each at or after its grid time;
- other TALC options on a later run: refused, the store untouched;
- the dashboard renders in headless Chromium (one plot per channel).

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import csv, os, random, re, signal, sqlite3, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from store_content import store_content  # noqa: E402
from html_render import check as render_check  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-live-")
check = Checks()
MACHINE = f"{SRC}/parts/machines/nmv5000.yaml"


def run(*args, **kw):
    return subprocess.run([PL, *args], capture_output=True, text=True, **kw)


# A 24 h campaign measured every 7 min (the plan's CP interval), the demo's truth.
part = f"{W}/artifact.yaml"
text, n = re.subn(r"(?m)^  count: \d+$", "  duration: 24 h", open(f"{SRC}/parts/sphere_artifact.yaml").read())
check("the artifact's duration could be set", n == 1, "")
open(part, "w").write(text)
p = run("plan", part, "--machine", MACHINE, "--out", f"{W}/plan")
check("plan", p.returncode == 0, p.stderr)
p = run("simulate", f"{W}/plan/sphere_cycle.nc", "--machine", MACHINE, "--part", part, "--truth",
        f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "5")
check("simulate", p.returncode == 0, p.stderr)
LOG, INPUTS = f"{W}/run/dprnt.txt", f"{W}/run/inputs.csv"
# TALC settings that exercise every phase in 24 h: a 6 h CP, hourly measurements, tight limits
# (NG phases), updates every 4 h.
TALC = ["--cp-h", "6", "--post-interval-h", "1", "--ng-interval-min", "15", "--ng-measurements", "4",
        "--update-interval-h", "4", "--limit-linear-um", "1.5", "--limit-angular-urad", "6", "--nb", "3"]


def content(store):
    return store_content(store, W)


# 1. The dense log replayed with --requested-only = the offline replay on the same data.
A = f"{W}/a.campaign"
p = run("campaign", "init", A, "--manifest", f"{W}/plan/plan.json")
check("init", p.returncode == 0, p.stderr)
p = run("campaign", "ingest", A, "--log", LOG, "--inputs", INPUTS, "--finished")
check("ingest", p.returncode == 0, p.stderr)
p = run("campaign", "export", A, "--out", f"{W}/export")
check("export", p.returncode == 0, p.stderr)
with open(f"{W}/export/errors.csv") as f:
    t = [float(r["time_s"]) for r in csv.DictReader(line for line in f if not line.startswith("#"))]
d = sorted(b - a for a, b in zip(t, t[1:]))
grid = repr(d[len(d) // 2])  # the replay's grid: the median spacing
p = run("campaign", "run", A, "--finished", "--requested-only", "--grid-s", grid, *TALC,
        "--html", f"{W}/dash.html", "--controller-file", f"{W}/controller.json")
check("campaign run (requested only)", p.returncode == 0, p.stderr)
live = p.stdout
p = run("model", "talc", "--inputs", f"{W}/export/inputs.csv", "--errors", f"{W}/export/errors.csv", *TALC)
check("model talc", p.returncode == 0, p.stderr)
replay = p.stdout


def table_rows(text):
    return [line.split() for line in text.splitlines() if re.match(r"^(P99_UC|P99_C|Reduction) ", line)]


check("Table 6.5 rows: live = replay", table_rows(live) == table_rows(replay) and len(table_rows(live)) == 3,
      f"{live}\n---\n{replay}")
taken_live = re.search(r"\((\d+) fed to TALC\)", live)
taken_replay = re.search(r"measurements taken: (\d+) of", replay)
check("measurements fed: live = replay", taken_live and taken_replay and taken_live[1] == taken_replay[1],
      f"{live}\n---\n{replay}")
ng_replay = re.search(r"NG phases: (\d+); parameter updates: (\d+) after NG, (\d+) periodic", replay)
db = sqlite3.connect(A)
ng_live = db.execute("SELECT COUNT(*) FROM talc_events WHERE action = 'NG start'").fetchone()[0]
starts_replay = sum(int(x) for x in re.search(r"NG starts\s+([\d\s]+)\n", replay)[1].split())
check(f"NG starts: live = replay ({ng_live}), and the settings start some", ng_live == starts_replay and ng_live > 0,
      f"{ng_live} vs {starts_replay}")
ups = db.execute("SELECT COUNT(*) FROM models").fetchone()[0]
check("model versions = first fit + updates of the replay",
      ng_replay and ups == 1 + int(ng_replay[2]) + int(ng_replay[3]), f"{ups} vs {ng_replay and ng_replay.groups()}")
ticks = db.execute("SELECT k, t_s, issued_s, applies_s FROM talc_ticks ORDER BY k").fetchall()
check("grid steps 0..K-1, each issued at or after its grid time, in order",
      [k for k, *_ in ticks] == list(range(len(ticks))) and all(i >= ts - 1e-9 and a == i for _, ts, i, a in ticks)
      and all(ticks[j][2] <= ticks[j + 1][2] for j in range(len(ticks) - 1)), "")
phases = [r[0] for r in db.execute("SELECT phase FROM phases ORDER BY seq")]
check("phase history CP -> compensation -> NG -> compensation ...",
      phases[:2] == ["CP", "compensation"] and "NG" in phases, f"{phases}")
db.close()
ok, detail = render_check(f"{W}/dash.html", 7)
check("the dashboard renders in Chromium (7 plots)", ok, detail)
ctl = open(f"{W}/controller.json").read()
check("the controller file says the phase, the wait and the compensation in effect",
      all(k in ctl for k in ('"phase"', '"wait_s"', '"compensation"', '"EY0C_um"')), ctl)

# 2. Other options on a later run: refused, the store untouched.
before = content(A)
p = run("campaign", "run", A, "--finished", "--requested-only", "--grid-s", grid, *TALC[:-2], "--nb", "4")
check("other TALC options: refused", p.returncode == 1 and "nb" in p.stderr and "fixed for a campaign" in p.stderr,
      p.stderr)
check("other TALC options: the store untouched", content(A) == before, "")

# 3. Written in pieces in time order, run after each piece, SIGKILLed at random instants.
events = []
log_lines = open(LOG).read().splitlines(keepends=True)
with open(f"{W}/run/points.csv") as f:
    point_times = [float(r["time_s"]) for r in csv.DictReader(line for line in f if not line.startswith("#"))]
pt, last = iter(point_times), 0.0
for line in log_lines:  # a line without a point (START, the closing %) goes with the one before it
    last = next(pt) if line.startswith("PT") else last
    events.append((last, 0, "log", line))
for line in open(INPUTS).read().splitlines(keepends=True):
    first = line.split(",")[0]
    events.append((float(first) if re.match(r"^[\d.]+$", first) else -1.0, 1, "in", line))
events.sort(key=lambda e: (e[0], e[1]))


def progress(store):
    """Steps stored so far (cycles evaluated, grid steps, measurements fed)."""
    try:
        db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
        n = sum(db.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0] for t in ("cycles", "talc_ticks", "talc_measurements"))
        db.close()
        return n
    except sqlite3.Error:
        return -1


def feed(store, folder, seed, kills):
    rng = random.Random(seed)
    os.makedirs(folder, exist_ok=True)
    log, inputs = f"{folder}/dprnt.txt", f"{folder}/inputs.csv"
    open(log, "w").close()
    open(inputs, "w").close()
    p = run("campaign", "init", store, "--manifest", f"{W}/plan/plan.json")
    check(f"init {os.path.basename(store)}", p.returncode == 0, p.stderr)
    n = 12
    cuts = sorted(rng.sample(range(1, len(events)), n - 1)) + [len(events)]
    at, killed, carry, duration, mid = 0, 0, {"log": "", "in": ""}, 0.05, []
    base = [PL, "campaign", "run", store, "--log", log, "--inputs", inputs, "--grid-s", grid, *TALC]
    for i, c in enumerate(cuts):
        piece = {"log": carry["log"], "in": carry["in"]}
        carry = {"log": "", "in": ""}
        for e in events[at:c]:
            piece[e[2]] += e[3]
        at = c
        if i < n - 1:  # tear the last line of each stream: its rest comes with the next piece
            for k in piece:
                s = piece[k]
                if len(s) > 1:
                    start = s.rfind("\n", 0, len(s) - 1) + 1
                    cut = rng.randrange(start, len(s))
                    piece[k], carry[k] = s[:cut], s[cut:]
        with open(log, "a") as f:
            f.write(piece["log"])
        with open(inputs, "a") as f:
            f.write(piece["in"])
        cmd = base + (["--finished"] if i == n - 1 else [])
        # Up to 6 kills per piece: half at a random instant within the measured length of a run
        # (after its first quarter, mostly process start-up), half right after a run's first
        # committed step.
        for _ in range(6 if kills else 0):
            if killed >= kills:
                break
            before = progress(store)
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            if rng.random() < 0.5:
                time.sleep(rng.uniform(0.25 * duration, duration))
            else:  # right after a step was committed (the store seen from outside, read-only)
                while proc.poll() is None and progress(store) <= before:
                    time.sleep(0.001)
            if proc.poll() is None:
                proc.send_signal(signal.SIGKILL)
                killed += 1
                proc.wait()
                mid.append((before, progress(store)))
            proc.wait()
        started = time.monotonic()
        p = subprocess.run(cmd, capture_output=True, text=True)
        after = progress(store)
        partial[0] += sum(1 for b, m in mid if b < m < after)
        mid.clear()
        duration = max(0.005, time.monotonic() - started)
        if p.returncode != 0:
            check(f"run after piece {i}", False, p.stderr)
            return killed
    return killed


U = f"{W}/uninterrupted.campaign"
run("campaign", "init", U, "--manifest", f"{W}/plan/plan.json")
p = run("campaign", "run", U, "--log", LOG, "--inputs", INPUTS, "--finished", "--grid-s", grid, *TALC)
check("uninterrupted run over the complete files", p.returncode == 0, p.stderr)
K = f"{W}/killed.campaign"
partial = [0]  # kills that landed after some of a run's steps were committed and before its last
killed = feed(K, f"{W}/feed", 7, kills=60)
check(f"at least 50 kills ({killed}), at least 10 of them between a run's committed steps ({partial[0]})",
      killed >= 50 and partial[0] >= 10, "")
cu, ck = content(U), content(K)
for t in cu:
    if t in ("log_sources", "input_source"):
        continue  # followed-file bookkeeping: the paths and read positions differ by construction
    check(f"table {t}: the killed, piecewise run = the uninterrupted run", cu[t] == ck.get(t),
          f"{len(cu[t])} vs {len(ck.get(t, []))} rows; first difference: " +
          str(next(((a, b) for a, b in zip(cu[t], ck.get(t, [])) if a != b), None)))

# 4. An input the models miss, named at an update and added while the loop runs: a loop that
#    starts with the hall temperature only.
D = f"{W}/d.campaign"
run("campaign", "init", D, "--manifest", f"{W}/plan/plan.json")
os.makedirs(f"{W}/feed-d", exist_ok=True)
DLOG, DIN = f"{W}/feed-d/dprnt.txt", f"{W}/feed-d/inputs.csv"
cut = next(i for i, e in enumerate(events) if e[0] > 10 * 3600)  # the first 10 h
open(DLOG, "w").write("".join(e[3] for e in events[:cut] if e[2] == "log"))
open(DIN, "w").write("".join(e[3] for e in events[:cut] if e[2] == "in"))
DTALC = ["--cp-h", "6", "--post-interval-h", "1", "--model-inputs", "T_env_C", "--grid-s", grid]
p = run("campaign", "run", D, "--log", DLOG, "--inputs", DIN, *DTALC)
check("run on the first 10 h (CP 6 h, T_env_C only)", p.returncode == 0, p.stderr)
m = re.search(r"the models miss (\S+) - start: .*; add it: (probeloop campaign add-input \S+ \S+)", p.stdout)
# The truth heats the C axis (EY, EZ, EA, EC) and, through it, the table (EX, EB, the artifact's
# growth: ER): either sensor is an input the hall temperature alone cannot replace.
check("the diagnosis names a temperature of the truth's heated nodes, with the command",
      m and m[1] in ("T_caxis_C", "T_table_C"), p.stdout[-800:])
affected = re.findall(r"\d+ % on (\w+)", p.stdout.split("the models miss")[1]) if m else []
if m:
    cmd = m[2].split()
    p = subprocess.run([PL] + cmd[1:], capture_output=True, text=True)
    check("the printed command runs", p.returncode == 0, p.stderr)
    p = subprocess.run([PL] + cmd[1:], capture_output=True, text=True)
    check("asked twice: refused", p.returncode == 1 and "requested already" in p.stderr, p.stderr)
p = run("campaign", "add-input", D, "T_nope")
check("an input the stream does not have: refused", p.returncode == 1 and "T_nope" in p.stderr, p.stderr)
open(DLOG, "a").write("".join(e[3] for e in events[cut:] if e[2] == "log"))
open(DIN, "a").write("".join(e[3] for e in events[cut:] if e[2] == "in"))
p = run("campaign", "run", D, "--log", DLOG, "--inputs", DIN, "--finished", *DTALC)
check("run to the end", p.returncode == 0, p.stderr)
p2 = run("campaign", "run", D, "--log", DLOG, "--inputs", DIN, "--finished", *DTALC)
check("a later run rebuilds the state with the input added where it was", p2.returncode == 0, p2.stderr)
db = sqlite3.connect(D)
added = db.execute("SELECT t_s FROM talc_input_changes").fetchone()
updates = [t for (t,) in db.execute("SELECT t_s FROM talc_events WHERE action LIKE '%update%' ORDER BY seq")]
used = next((t for t in updates if added and t > added[0]), None)
check("the input is taken at the next pass and used from the next update", added and used, f"{added} {updates}")


def p99(values):
    v = sorted(abs(x) for x in values)
    h = 0.99 * (len(v) + 1) - 1
    i = min(max(int(h), 0), len(v) - 1)
    return v[i] if i + 1 >= len(v) else v[i] + (h - i) * (v[i + 1] - v[i])


if used:
    for ch in affected:
        rows = db.execute("SELECT m.t_s, r.residual FROM residuals r JOIN talc_measurements m USING (cycle) "
                          "WHERE r.channel = ? AND r.residual IS NOT NULL", (ch,)).fetchall()
        before = [r for t, r in rows if t <= used]
        after = [r for t, r in rows if t > used]
        check(f"{ch}: the compensated P99 falls after that update ({p99(before):.2f} -> {p99(after):.2f}, "
              f"{len(before)} and {len(after)} measurements)", before and after and p99(after) < p99(before), "")
db.close()
check.finish()
