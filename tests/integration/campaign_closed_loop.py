#!/usr/bin/env python3
"""The live TALC loop closed on the virtual machine (issue 30 item 4), through the real CLI.

A 72 h sphere campaign of the demo's truth (C-axis duty, day/night hall, and the hall door
opening at 30 h: -3 K for 9 h) runs with `simulate --live`: the emitted Fanuc program reads
its wait from #500, the live loop issues offsets that the machine applies, and the campaign
store records every step. Calibration phase 24 h, then a measurement every hour (seed 004:
"every 1-2 h"), action limits 5 um and 15 um/m.

- the program follows TALC: cycles every grid step (the plan's cycle period) in the CP, then
  hourly, and every 10 min in the No-Good phase;
- the door (after the CP) starts an NG phase, which ends with a parameter update after its
  12 measurements; every compensated measurement after that update lies within the action
  limits;
- on the measurements after the CP, the compensated P99 (what the machine measured with the
  offsets applied) is smaller than the uncompensated one for every error, and each reduction
  is at least the offline replay's (`model talc`, same options) on the densely measured
  uncompensated campaign of the same truth and seed;
- two runs give byte-identical logs and the same store content (the closed loop is as
  deterministic as the open one); the dashboard renders in Chromium.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import os, re, sqlite3, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from store_content import store_content  # noqa: E402
from html_render import check as render_check  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-closed-")
check = Checks()
MACHINE = f"{SRC}/parts/machines/nmv5000.yaml"
TRUTH = f"{SRC}/examples/truth_campaign.yaml"
TALC = ["--cp-h", "24", "--post-interval-h", "1"]
LIMIT = {"um": 5.0, "urad": 15.0}


def run(*args):
    return subprocess.run([PL, *args], capture_output=True, text=True)


base = open(f"{SRC}/parts/sphere_artifact.yaml").read()
dense, n = re.subn(r"(?m)^  count: \d+$", "  duration: 72 h", base)
live = dense.replace("  duration: 72 h", "  duration: 72 h\n  live_interval: true")
check("the artifact's duration could be set", n == 1 and live != dense, "")
for name, text in (("dense", dense), ("live", live)):
    open(f"{W}/{name}.yaml", "w").write(text)
    p = run("plan", f"{W}/{name}.yaml", "--machine", MACHINE, "--out", f"{W}/plan-{name}")
    check(f"plan ({name})", p.returncode == 0, p.stderr)
program = open(f"{W}/plan-live/sphere_cycle.nc").read()
check("the live program reads its wait from #500", "#101=#500" in program, "")


def closed_loop(tag):
    store = f"{W}/{tag}.campaign"
    p = run("campaign", "init", store, "--manifest", f"{W}/plan-live/plan.json")
    check(f"init {tag}", p.returncode == 0, p.stderr)
    p = run("simulate", f"{W}/plan-live/sphere_cycle.nc", "--machine", MACHINE, "--part", f"{W}/live.yaml", "--truth",
            TRUTH, "--out", f"{W}/{tag}", "--seed", "1", "--live", store, "--until-h", "72", *TALC)
    check(f"simulate --live ({tag})", p.returncode == 0, p.stderr)
    return store, p.stdout


def table(text):
    """Table 6.5's rows: {P99_UC: [...], P99_C: [...], Reduction: [...]} as numbers."""
    out = {}
    for line in text.splitlines():
        m = re.match(r"^(P99_UC|P99_C|Reduction)\s+(.*)$", line)
        if m:
            out[m[1]] = [float(x) for x in re.findall(r"-?\d+\.\d", m[2])]
    return out


A, out_a = closed_loop("a")
db = sqlite3.connect(A)
meas = db.execute("SELECT cycle, t_s, phase_before, taken FROM talc_measurements ORDER BY cycle").fetchall()
events = db.execute("SELECT t_s, channel, residual, action FROM talc_events ORDER BY seq").fetchall()
grid = float(re.search(r'"grid_s":([0-9.]+)', db.execute("SELECT json FROM talc_config").fetchone()[0])[1])

# The schedule the program followed.
cp = [t for _, t, ph, _ in meas if ph == "CP"]
gaps = [b - a for a, b in zip(cp, cp[1:])]
check(f"CP: a cycle every grid step ({grid:.1f} s), {len(cp)} cycles", gaps and all(abs(g - grid) < 5 for g in gaps),
      f"{min(gaps)} .. {max(gaps)}")
post = [(t, ph) for _, t, ph, _ in meas if ph == "compensation"]
hourly = [b[0] - a[0] for a, b in zip(post, post[1:]) if a[1] == b[1] == "compensation"]
check("after the CP: hourly (+-2 min) between compensation-phase cycles",
      hourly and sum(1 for g in hourly if abs(g - 3600) < 120) >= len(hourly) - 2, f"{hourly}")
ng = [t for _, t, ph, _ in meas if ph == "NG"]
ng_gaps = [b - a for a, b in zip(ng, ng[1:])]
check("NG: 12 measurements, every 10 min (+-1 min)",
      len(ng) == 12 and all(abs(g - 600) < 60 for g in ng_gaps), f"{len(ng)}: {ng_gaps}")

# The door.
starts = [(t, c, r) for t, c, r, a in events if a == "NG start"]
check("the door (30 h) starts an NG phase within 3 h, after the CP", starts and 30 * 3600 < starts[0][0] < 33 * 3600,
      f"{starts}")
after = [t for t, c, r, a in events if a == "update after NG"]
check("the NG phase ends with a parameter update", len(after) == len(starts) >= 1, f"{events}")
rows = db.execute("SELECT m.t_s, r.channel, r.measured FROM residuals r JOIN talc_measurements m USING (cycle) "
                  "WHERE m.applied_k IS NOT NULL ORDER BY m.t_s").fetchall()
beyond = [(round(t / 3600, 2), ch, round(v, 2)) for t, ch, v in rows
          if after and t > after[-1] and abs(v) > LIMIT[ch.split("_")[1]]]
check("after that update, every compensated measurement within the action limits", not beyond and rows, f"{beyond}")
db.close()

# Against the offline replay of the uncompensated, densely measured campaign.
p = run("simulate", f"{W}/plan-dense/sphere_cycle.nc", "--machine", MACHINE, "--part", f"{W}/dense.yaml", "--truth",
        TRUTH, "--out", f"{W}/dense", "--seed", "1")
check("simulate the dense uncompensated campaign", p.returncode == 0, p.stderr)
p = run("evaluate", f"{W}/dense/points.csv", "--format", "csv", "--manifest", f"{W}/plan-dense/plan.json",
        "--out", f"{W}/dense-eval")
check("evaluate it", p.returncode == 0, p.stderr)
p = run("model", "talc", "--inputs", f"{W}/dense/inputs.csv", "--errors", f"{W}/dense-eval/errors.csv", *TALC)
check("model talc on it", p.returncode == 0, p.stderr)
live_t, replay_t = table(out_a), table(p.stdout)
print("closed loop:\n" + "\n".join(line for line in out_a.splitlines() if line.startswith(("P99", "Red", " "))))
print("offline replay:\n" + "\n".join(line for line in p.stdout.splitlines() if line.startswith(("P99", "Red", " "))))
ok = len(live_t.get("Reduction", [])) == 7 and len(replay_t.get("Reduction", [])) == 7
check("both give Table 6.5 for the seven errors", ok, f"{live_t}\n{replay_t}")
if ok:
    check("the compensated P99 below the uncompensated one, every error",
          all(c < u for c, u in zip(live_t["P99_C"], live_t["P99_UC"])), f"{live_t}")
    check("every reduction at least the offline replay's",
          all(a >= b for a, b in zip(live_t["Reduction"], replay_t["Reduction"])),
          f"{live_t['Reduction']} vs {replay_t['Reduction']}")

# Deterministic.
B, out_b = closed_loop("b")
check("two runs: byte-identical logs", open(f"{W}/a/dprnt.txt", "rb").read() == open(f"{W}/b/dprnt.txt", "rb").read(), "")


def content(store):
    return store_content(store, skip=("log_sources", "input_source"))


ca, cb = content(A), content(B)
check("two runs: the same store content, table by table", ca == cb,
      [t for t in ca if ca[t] != cb.get(t)])
ok, detail = render_check(f"{W}/a/live/dashboard.html", 7)
check("the dashboard renders in Chromium (7 plots)", ok, detail)
check.finish()
