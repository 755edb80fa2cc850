#!/usr/bin/env python3
"""Outputs that survive a crash (issue 17 item 3): `simulate` (the thermal test piece's three
programs) and `evaluate` (its DPRNT log) are killed at many moments of their run, SIGKILL and
SIGINT, over the outputs of an earlier run with another seed. Afterwards every output file
must be byte-identical to the old run's or to an uninterrupted new run's, never anything
else; after SIGINT no temporary file may be left; after SIGKILL only temporaries named
"<output>.tmp-<pid>-<n>" beside the outputs (a command's outputs are written as temporaries
and renamed into place together when it has succeeded, issue 28: a SIGKILL before that leaves
every output old). The kill moments are spread over the whole run (measured first), so some
land while the outputs are being written; the test counts the runs that left a mix of old and
new files (only a kill between two renames of the commit can).

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import os, re, shutil, signal, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-interrupt-")
check = Checks()
MACHINE = f"{SRC}/parts/machines/nmv5000.yaml"
PART = f"{SRC}/parts/thermal_test_piece.yaml"

p = subprocess.run([PL, "plan", PART, "--machine", MACHINE, "--out", f"{W}/plan"], capture_output=True, text=True)
check("plan", p.returncode == 0, p.stderr)
programs = [f"{W}/plan/{n}" for n in ("pre_machining.nc", "thermal_test.nc", "inspection.nc")]


def simulate(out, seed):
    return [PL, "simulate", *programs, "--machine", MACHINE, "--part", PART, "--truth",
            f"{SRC}/examples/truth_thermal_test.yaml", "--out", out, "--seed", str(seed)]


def evaluate(log, out):
    return [PL, "evaluate", log, "--manifest", f"{W}/plan/plan.json", "--out", out]


def contents(folder):
    return {n: open(os.path.join(folder, n), "rb").read() for n in sorted(os.listdir(folder))}


def torture(name, command_for, old_dir, new_dir, kills):
    """Runs command_for(target) over a copy of old_dir, killed at each moment; checks each file."""
    old, new = contents(old_dir), contents(new_dir)
    check(f"{name}: old and new runs differ (else the test shows nothing)",
          any(old.get(k) != v for k, v in new.items()), "")
    t0 = time.monotonic()
    subprocess.run(command_for(f"{W}/timing-{name}"), capture_output=True)
    duration = time.monotonic() - t0
    # About 30 s of kills at most: a sanitizer build runs the commands 30-50x slower.
    kills = max(8, min(kills, int(30.0 / max(duration, 1e-3) / 0.6)))
    mixed = all_new = torn = stray_int = 0
    stray_kill = []
    for i in range(kills):
        sig = signal.SIGKILL if i % 2 == 0 else signal.SIGINT
        # Half the kills spread over the whole run, half over its last 15 % (the writing).
        half = kills // 2
        at = duration * ((i + 0.5) / half if i < half else 0.9 + 0.15 * (i - half + 0.5) / (kills - half))
        target = f"{W}/{name}-{i}"
        shutil.copytree(old_dir, target)
        proc = subprocess.Popen(command_for(target), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(at)
        proc.send_signal(sig)
        proc.wait()
        now = contents(target)
        temporaries = [n for n in now if re.search(r"\.tmp-\d+(-\d+)?$", n)]
        finals = {n: b for n, b in now.items() if n not in temporaries}
        for n, b in finals.items():
            if b != old.get(n) and b != new.get(n):
                torn += 1
                print(f"  {name}: {n} after {sig.name} at {at:.3f} s is neither the old nor the new file")
        got_new = any(finals.get(n) == b for n, b in new.items() if old.get(n) != b)
        got_old = any(finals.get(n) == b for n, b in old.items() if new.get(n) != b)
        mixed += got_new and got_old
        all_new += got_new and not got_old
        if sig == signal.SIGINT:
            stray_int += len(temporaries)
        else:  # each beside the output it was to become
            stray_kill += [t for t in temporaries if re.sub(r"\.tmp-\d+(-\d+)?$", "", t) not in new]
        shutil.rmtree(target)
    print(f"  {name}: {kills} kills over a {duration:.3f} s run: {kills - mixed - all_new} left the old "
          f"files, {mixed} old and new side by side, {all_new} the new ones")
    check(f"{name}: every file is the old one or the new one after {kills} kills", torn == 0, "")
    check(f"{name}: SIGINT leaves no temporary file", stray_int == 0, f"{stray_int} left")
    check(f"{name}: SIGKILL leaves only the pending outputs' temporaries beside them", not stray_kill, str(stray_kill))


# Old outputs (seed 2), new outputs (seed 1): every output differs between the two.
for seed, out in ((2, f"{W}/old-run"), (1, f"{W}/new-run")):
    p = subprocess.run(simulate(out, seed), capture_output=True, text=True)
    check(f"simulate seed {seed}", p.returncode == 0, p.stderr)
torture("simulate", lambda target: simulate(target, 1), f"{W}/old-run", f"{W}/new-run", 40)

for run, out in (("old-run", f"{W}/old-eval"), ("new-run", f"{W}/new-eval")):
    p = subprocess.run(evaluate(f"{W}/{run}/dprnt.txt", out), capture_output=True, text=True)
    check(f"evaluate {run}", p.returncode == 0, p.stderr)
torture("evaluate", lambda target: evaluate(f"{W}/new-run/dprnt.txt", target), f"{W}/old-eval", f"{W}/new-eval", 40)

# An interrupted run does not report success: SIGINT's status is 128 + 2 (the shell's 130).
proc = subprocess.Popen(simulate(f"{W}/sigint-status", 1), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
time.sleep(0.01)
proc.send_signal(signal.SIGINT)
check("SIGINT ends the run with the signal's status", proc.wait() == -signal.SIGINT, f"status {proc.returncode}")

shutil.rmtree(W)
check.finish()
