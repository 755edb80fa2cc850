#!/usr/bin/env python3
"""The campaign store through the real CLI (issue 30 items 1 and 5): a simulated sphere campaign's
LinuxCNC log and inputs are written in pieces, as a controller and a data logger write them
(torn lines included), and ingested after each piece.

- `campaign export` gives the errors.csv `evaluate` gives on the whole log (every value, and the
  last cycle's row to the last digit) and the inputs.csv `simulate` wrote, byte for byte;
- `campaign ingest` killed with SIGKILL at random instants (at least 50 kills) while the log
  grows, then run again: the final store holds exactly what an uninterrupted run stored, table
  by table (no cycle lost, none twice);
- bad input: a log of another plan, a cycle with missing points, an inputs stream whose clock
  goes backwards, a store of a newer schema: a clear error (exit 1) and the store untouched;
- `campaign status` on a store and on a folder of stores.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import csv, os, random, re, shutil, signal, sqlite3, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from store_content import store_content  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-campaign-")
check = Checks()
MACHINE = f"{SRC}/parts/machines/linuxcnc_rotary_mill.yaml"


def run(*args, **kw):
    return subprocess.run([PL, *args], capture_output=True, text=True, **kw)


# A 10-cycle campaign of the demo's truth on the LinuxCNC mill.
part = f"{W}/artifact.yaml"
with open(f"{SRC}/parts/sphere_artifact.yaml") as f:
    text = f.read()
text, n = re.subn(r"(?m)^  count: \d+$", "  count: 10", text)
check("the artifact's cycle count could be set", n == 1, "")
with open(part, "w") as f:
    f.write(text)
p = run("plan", part, "--machine", MACHINE, "--out", f"{W}/plan")
check("plan", p.returncode == 0, p.stderr)
p = run("simulate", f"{W}/plan/sphere_cycle.ngc", "--machine", MACHINE, "--part", part, "--truth",
        f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "3")
check("simulate", p.returncode == 0, p.stderr)
LOG, INPUTS = f"{W}/run/sphere_probe.log", f"{W}/run/inputs.csv"
p = run("evaluate", LOG, "--manifest", f"{W}/plan/plan.json", "--out", f"{W}/offline")
check("evaluate offline", p.returncode == 0, p.stderr)
log_bytes, input_bytes = open(LOG, "rb").read(), open(INPUTS, "rb").read()


def pieces(data, count, rng):
    """`data` cut at `count` random byte positions (mid-line, mid-number)."""
    cuts = sorted(rng.sample(range(1, len(data)), count)) + [len(data)]
    out, at = [], 0
    for c in cuts:
        out.append(data[at:c])
        at = c
    return out


def grow(store, folder, seed, kills=0):
    """Writes the log and inputs in pieces into `folder`, ingesting after each; with kills > 0 some
    ingests are SIGKILLed at a random instant and the ingest is then run again."""
    rng = random.Random(seed)
    os.makedirs(folder, exist_ok=True)
    log, inputs = f"{folder}/sphere_probe.log", f"{folder}/inputs.csv"
    open(log, "wb").close()
    open(inputs, "wb").close()
    p = run("campaign", "init", store, "--manifest", f"{W}/plan/plan.json")
    check(f"init {os.path.basename(store)}", p.returncode == 0, p.stderr)
    n = 40
    lp, ip = pieces(log_bytes, n - 1, rng), pieces(input_bytes, n - 1, rng)
    killed, durations = 0, []
    for i in range(n):
        with open(log, "ab") as f:
            f.write(lp[i])
        with open(inputs, "ab") as f:
            f.write(ip[i])
        cmd = [PL, "campaign", "ingest", store, "--log", log, "--inputs", inputs] + (["--finished"] if i == n - 1 else [])
        # Up to 3 kills per piece: at a random instant within the measured length of an ingest.
        for _ in range(3 if kills else 0):
            if killed >= kills:
                break
            typical = sorted(durations)[len(durations) // 2] if durations else 0.05
            q = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            time.sleep(rng.uniform(0, 1.2 * typical))
            q.send_signal(signal.SIGKILL)
            q.wait()
            killed += 1
        t0 = time.monotonic()
        p = subprocess.run(cmd, capture_output=True, text=True)
        durations.append(time.monotonic() - t0)
        if p.returncode != 0:
            check(f"ingest piece {i}", False, p.stderr)
            return killed
    return killed


def content(store):
    return store_content(store, W)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


# 1. Ingested in pieces: the offline results.
A = f"{W}/a.campaign"
grow(A, f"{W}/grow-a", 1)
p = run("campaign", "export", A, "--out", f"{W}/export-a")
check("export", p.returncode == 0, p.stderr)
live, offline = rows(f"{W}/export-a/errors.csv"), rows(f"{W}/offline/errors.csv")
check("every cycle evaluated once", [r["cycle"] for r in live] == [r["cycle"] for r in offline],
      f"{[r['cycle'] for r in live]} vs {[r['cycle'] for r in offline]}")
names = [k for k in offline[0] if k not in ("time_s", "cycle") and not k.startswith("U_")]
check("every value as the offline evaluation", all(a[k] == b[k] for a, b in zip(live, offline) for k in ["time_s"] + names),
      "")
last_live = open(f"{W}/export-a/errors.csv").read().strip().splitlines()[-1]
last_offline = open(f"{W}/offline/errors.csv").read().strip().splitlines()[-1]
check("the last cycle's row (U pooled over every cycle) to the last digit", last_live == last_offline,
      f"{last_live}\n{last_offline}")
# U of an earlier cycle: the offline evaluation of the log cut after that cycle.
per_cycle = sum(1 for line in log_bytes.decode().splitlines() if float(line.split()[1]) == 1)
cut = "".join(line + "\n" for line in log_bytes.decode().splitlines()[:4 * per_cycle])
with open(f"{W}/cut4.log", "w") as f:
    f.write(cut)
p = run("evaluate", f"{W}/cut4.log", "--manifest", f"{W}/plan/plan.json", "--out", f"{W}/offline4")
check("evaluate the log cut after cycle 4", p.returncode == 0, p.stderr)
row4 = [line for line in open(f"{W}/export-a/errors.csv").read().splitlines() if line.split(",")[1:2] == ["4"]]
off4 = [line for line in open(f"{W}/offline4/errors.csv").read().splitlines() if line.split(",")[1:2] == ["4"]]
check("cycle 4's row as evaluate gives it on the log cut after cycle 4", row4 == off4 and row4, f"{row4}\n{off4}")
check("inputs.csv exported as simulate wrote it", open(f"{W}/export-a/inputs.csv", "rb").read() == input_bytes, "")
p = subprocess.run([PL, "model", "talc", "--inputs", f"{W}/export-a/inputs.csv", "--errors", f"{W}/export-a/errors.csv",
                    "--cp-h", "0"], capture_output=True, text=True)
check("the exported CSVs are read by `model talc` (exit 0 or a reasoned refusal)",
      p.returncode == 0 or "CP" in p.stderr or "calibration" in p.stderr, p.stderr)

# 2. SIGKILL at random instants: the same store content.
B = f"{W}/b.campaign"
killed = grow(B, f"{W}/grow-b", 1, kills=60)
check(f"at least 50 kills ({killed})", killed >= 50, "")
ca, cb = content(A), content(B)
for t in ca:
    check(f"killed run's table {t} identical to the uninterrupted run's", ca[t] == cb.get(t),
          f"{len(ca[t])} vs {len(cb.get(t, []))} rows")

# 3. Bad input: refused, the store untouched.
before = content(A)


def refused(name, args, needle):
    p = run(*args)
    check(f"{name}: refused", p.returncode == 1 and needle in p.stderr, p.stderr or p.stdout)
    check(f"{name}: the store untouched", content(A) == before, "")


other = f"{W}/other.log"
with open(other, "w") as f:
    for line in log_bytes.decode().splitlines():
        t = line.split()
        f.write(f"PT {t[1]} {t[2]} {t[3]} {float(t[4]) + 40:.6f} {t[5]} {t[6]}\n")
refused("a log of another plan", ["campaign", "ingest", A, "--log", other], "does not match the manifest")
with open(f"{W}/grow-a/inputs.csv", "a") as f:
    header = next(line for line in input_bytes.decode().splitlines() if not line.startswith("#"))
    f.write("10,20.0" + ",0" * (len(header.split(",")) - 2) + "\n")
refused("an inputs clock going backwards", ["campaign", "ingest", A, "--inputs", f"{W}/grow-a/inputs.csv"], "backwards")
with open(f"{W}/grow-a/sphere_probe.log", "r+b") as f:
    f.truncate(len(log_bytes) // 2)
refused("a log that shrank", ["campaign", "ingest", A, "--log", f"{W}/grow-a/sphere_probe.log"], "replaced or truncated")
newer = f"{W}/newer.campaign"
shutil.copy(A, newer)
db = sqlite3.connect(newer)
db.execute("PRAGMA user_version = 3")
db.close()
newer_bytes = open(newer, "rb").read()
p = run("campaign", "status", newer)
check("a store of a newer schema: refused", p.returncode == 1 and "schema version 3" in p.stderr, p.stderr)
check("a store of a newer schema: untouched", open(newer, "rb").read() == newer_bytes, "")
p = run("campaign", "init", A, "--manifest", f"{W}/plan/plan.json")
check("init over an existing store: refused", p.returncode == 1 and "already exists" in p.stderr, p.stderr)

# A cycle with missing points: kept as incomplete, the rest evaluated.
C = f"{W}/c.campaign"
run("campaign", "init", C, "--manifest", f"{W}/plan/plan.json")
lines = log_bytes.decode().splitlines()
gappy = [line for line in lines if not (float(line.split()[1]) == 3 and line.split()[2] == "2" and int(line.split()[3]) > 2)]
with open(f"{W}/gappy.log", "w") as f:
    f.write("\n".join(gappy[:len(gappy) // 2]) + "\nPT 1 1 garbage\n" + "\n".join(gappy[len(gappy) // 2:]) + "\n")
p = run("campaign", "ingest", C, "--log", f"{W}/gappy.log", "--finished")
check("a log with a gap and a garbled line: ingested", p.returncode == 0, p.stderr)
p = run("campaign", "status", C)
check("status names the incomplete cycle and why", "cycle 3 incomplete: position 2: 2 points" in p.stdout, p.stdout)
check("status names the quarantined line", "quarantined: " in p.stdout and "gappy.log:" in p.stdout, p.stdout)
check("the other cycles evaluated", "9 evaluated" in p.stdout, p.stdout)

# 4. A folder of stores.
fleet = f"{W}/fleet"
os.makedirs(fleet)
for name in ("m1.campaign", "m2.campaign"):
    shutil.copy(A, f"{fleet}/{name}")
p = run("campaign", "status", fleet)
out = list(csv.DictReader(p.stdout.splitlines()))
check("fleet status: one row per store", p.returncode == 0 and len(out) == 2 and out[0]["cycles_evaluated"] == "10",
      p.stdout + p.stderr)
with open(f"{fleet}/notes.txt", "w") as f:
    f.write("not a store\n")
p = run("campaign", "status", fleet)
check("fleet status: a file that is not a store is named, exit 1",
      p.returncode == 1 and "notes.txt" in p.stderr and len(list(csv.DictReader(p.stdout.splitlines()))) == 2, p.stderr)

shutil.rmtree(W)
check.finish()
