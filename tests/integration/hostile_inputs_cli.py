#!/usr/bin/env python3
"""Hostile inputs through the real CLI (issue 28, docs/reliability.md#opening-inputs): the shapes
a hostile-input suite written outside the project found, each now refused with a message that
names the file, and exit 2 where the input is not a file at all.

1. Not a regular file: a FIFO with no writer (every reader blocked for ever), /dev/zero (read
   until memory ran out), a folder, a symbolic-link loop: refused at once, exit 2, the path named.
2. A YAML key written twice (plan, gum, model fit): refused with both lines, nothing written.
3. Files of another kind: a QIF with a DOCTYPE and a UTF-16 QIF handed to `evaluate` of a
   sphere campaign (taken for a probe log before), an empty log (no file named before); a
   UTF-16 CSV is read as the same points as its UTF-8 original.
4. A 2 MB token is echoed in a few dozen characters.
5. All or nothing: `evaluate --scene` into a place that cannot be written fails and leaves the
   other outputs as they were (new ones absent, old ones unchanged).
6. An endless loop with moves is refused by `check` within seconds (the bound of
   gcode/interpreter.hpp), naming the line.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import os, shutil, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-hostile-")
check = Checks()
MACHINE = f"{SRC}/parts/machines/linuxcnc_rotary_mill.yaml"
ARTIFACT = f"{SRC}/parts/sphere_artifact.yaml"


def run(*args, timeout=60):
    t0 = time.time()
    try:
        p = subprocess.run([PL, *args], capture_output=True, text=True, timeout=timeout, errors="replace")
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired:
        return None, "", f"timed out after {timeout} s", time.time() - t0


code, o, e, _ = run("plan", ARTIFACT, "--machine", MACHINE, "--out", f"{W}/plan")
check("plan the sphere artifact", code == 0, e)
MANIFEST = f"{W}/plan/plan.json"
code, o, e, _ = run("synth", MANIFEST, "--truth", f"{SRC}/examples/truth_rigid.yaml", "--out", f"{W}/run")
check("synth its logs", code == 0, e)
LOG = f"{W}/run/sphere_probe.log"

# --- 1. not a regular file -----------------------------------------------------------------------
fifo = f"{W}/pipe.yaml"
os.mkfifo(fifo)
os.mkdir(f"{W}/folder.ngc")
os.symlink(f"{W}/loop_b.csv", f"{W}/loop_a.csv")
os.symlink(f"{W}/loop_a.csv", f"{W}/loop_b.csv")
cases = [
    ("a FIFO as the test piece of plan", ["plan", fifo, "--machine", MACHINE, "--out", f"{W}/x"], fifo, "named pipe"),
    ("a FIFO as the log of evaluate", ["evaluate", fifo, "--manifest", MANIFEST, "--out", f"{W}/x"], fifo, "named pipe"),
    ("/dev/zero to read", ["read", "/dev/zero"], "/dev/zero", "is a device"),
    ("a folder as a program of check", ["check", f"{W}/folder.ngc", "--machine", MACHINE, "--part", ARTIFACT],
     f"{W}/folder.ngc", "is a folder"),
    ("a link loop to fit", ["fit", "sphere", f"{W}/loop_a.csv"], f"{W}/loop_a.csv", "loop of symbolic links"),
    ("a FIFO as the model of model fit", ["model", "fit", fifo], fifo, "named pipe"),
]
for name, args, path, what in cases:
    code, o, e, dt = run(*args, timeout=30)
    check(f"{name}: exit 2 in {dt:.1f} s naming the path ({what})", code == 2 and path in e and what in e and dt < 10,
          (code, e[:400]))

# --- 2. a key written twice -------------------------------------------------------------------------
def twice(src, key_line, dup_line, dst):
    text = open(src).read()
    assert key_line in text, key_line
    open(dst, "w").write(text.replace(key_line, key_line + "\n" + dup_line, 1))
    first = text[:text.index(key_line)].count("\n") + 1
    return first


first = twice(ARTIFACT, "  diameter: 30 mm", "  diameter: 3000 mm", f"{W}/dup_artifact.yaml")
code, o, e, _ = run("plan", f"{W}/dup_artifact.yaml", "--machine", MACHINE, "--out", f"{W}/dup_plan")
check("plan: a key written twice is refused with both lines, nothing written",
      code != 0 and f"dup_artifact.yaml:{first + 1}: key 'diameter' is written twice (lines {first} and {first + 1})" in e
      and not os.path.exists(f"{W}/dup_plan"), (code, e[:400]))
gum = f"{SRC}/examples/gum/end_gauge_h1.yaml"
gum_text = open(gum).read()
title = next(l for l in gum_text.split("\n") if l.startswith("title:"))
first = twice(gum, title, "title: again", f"{W}/dup_gum.yaml")
code, o, e, _ = run("gum", f"{W}/dup_gum.yaml")
check("gum: a key written twice is refused with both lines", code != 0 and "key 'title' is written twice" in e
      and f"(lines {first} and {first + 1})" in e, (code, e[:400]))
model = f"{SRC}/examples/model/start.yaml"
kind = next(l for l in open(model).read().split("\n") if l.startswith("kind:"))
first = twice(model, kind, kind, f"{W}/dup_model.yaml")
code, o, e, _ = run("model", "fit", f"{W}/dup_model.yaml")
check("model fit: a key written twice is refused with both lines", code != 0 and "key 'kind' is written twice" in e
      and f"(lines {first} and {first + 1})" in e, (code, e[:400]))

# --- 3. files of another kind ------------------------------------------------------------------------
qif = ('<?xml version="1.0" encoding="UTF-16"?>\n<!DOCTYPE QIFDocument [<!ENTITY a "1 2 3">]>\n'
       '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0"></QIFDocument>\n')
open(f"{W}/doctype.qif", "w").write(qif.replace(' encoding="UTF-16"', ""))
open(f"{W}/utf16.qif", "wb").write(qif.replace("<!DOCTYPE QIFDocument [<!ENTITY a \"1 2 3\">]>\n", "").encode("utf-16"))
for f in ("doctype.qif", "utf16.qif"):
    code, o, e, _ = run("evaluate", f"{W}/{f}", "--manifest", MANIFEST, "--out", f"{W}/x")
    check(f"evaluate a sphere campaign from {f}: named as a QIF document, not misread as a log",
          code == 1 and f"{f}: this is a QIF (XML) document" in e and "unrecognised" not in e, (code, e[:400]))
code, o, e, _ = run("read", f"{W}/utf16.qif")
check("read: the UTF-16 QIF is read (transcoded)", code == 0, (code, e[:400]))
open(f"{W}/empty.log", "w").close()
code, o, e, _ = run("evaluate", f"{W}/empty.log", "--manifest", MANIFEST, "--out", f"{W}/x")
check("evaluate an empty log: the file is named", code == 1 and f"{W}/empty.log" in e, (code, e[:400]))
code, o, e, _ = run("evaluate", MANIFEST, "--manifest", LOG, "--out", f"{W}/x")
check("evaluate with the log and the manifest swapped: the manifest option says what it got",
      code == 1 and "looks like a probe log" in e, (code, e[:400]))
pts = "x_mm,y_mm,z_mm\n" + "".join(f"{x},{y},{z}\n" for x, y, z in
                                   ((12.5, 0, 0), (-12.5, 0, 0), (0, 12.5, 0), (0, -12.5, 0), (0, 0, 12.5),
                                    (8.8388, 8.8388, 0.0), (0, 8.8388, 8.8388)))
open(f"{W}/ball.csv", "w").write(pts)
open(f"{W}/ball16.csv", "wb").write(pts.encode("utf-16"))
a = run("fit", "sphere", f"{W}/ball.csv")
b = run("fit", "sphere", f"{W}/ball16.csv")
check("fit: a UTF-16 CSV gives the same sphere as its UTF-8 original", a[0] == 0 and b[0] == 0 and
      a[1].replace("ball.csv", "F") == b[1].replace("ball16.csv", "F"), (a[2][:300], b[2][:300]))

# --- 4. a huge token ---------------------------------------------------------------------------------
open(f"{W}/huge.log", "w").write("PT 1 1 1 " + "9" * 2_000_000 + " 0 0\n")
code, o, e, _ = run("evaluate", f"{W}/huge.log", "--manifest", MANIFEST, "--out", f"{W}/x")
check("a 2 MB token: refused, stderr under 1 KB", code == 1 and 0 < len(e) < 1024 and "huge.log:1:" in e, (code, len(e), e[:300]))

# --- 5. all or nothing --------------------------------------------------------------------------------
code, o, e, _ = run("evaluate", LOG, "--manifest", MANIFEST, "--out", f"{W}/eval", "--scene", "/proc/probeloop/x.gltf")
check("evaluate --scene into /proc: fails and writes none of its outputs", code == 1 and not (
    os.path.exists(f"{W}/eval") and os.listdir(f"{W}/eval")), (code, e[:300], os.listdir(f"{W}/eval") if os.path.exists(f"{W}/eval") else ""))
code, o, e, _ = run("evaluate", LOG, "--manifest", MANIFEST, "--out", f"{W}/eval")
check("evaluate without the scene: its outputs", code == 0 and "errors.csv" in os.listdir(f"{W}/eval"), e[:300])
before = {n: open(f"{W}/eval/{n}", "rb").read() for n in os.listdir(f"{W}/eval")}
code, o, e, _ = run("evaluate", LOG, "--manifest", MANIFEST, "--out", f"{W}/eval", "--free-radius",
                    "--scene", "/proc/probeloop/x.gltf")
after = {n: open(f"{W}/eval/{n}", "rb").read() for n in os.listdir(f"{W}/eval")}
check("the same over earlier outputs: every old output unchanged, no temporary left", code == 1 and before == after,
      (code, sorted(after)))

# --- 6. an endless loop with moves ---------------------------------------------------------------------
lines = open(f"{W}/plan/sphere_cycle.ngc").read().split("\n")
i = next(k for k, l in enumerate(lines) if l.startswith("G43 H99"))
lines[i + 1:i + 1] = ["o900 while [1]", "G91 G0 X0.001", "G0 X-0.001", "G90", "o900 endwhile"]
open(f"{W}/endless.ngc", "w").write("\n".join(lines))
code, o, e, dt = run("check", f"{W}/endless.ngc", "--machine", MACHINE, "--part", ARTIFACT, timeout=120)
check(f"check: an endless loop with moves refused in {dt:.1f} s (exit 2, 'endless loop')",
      code == 2 and "endless loop" in e and "endless.ngc:" in e, (code, e[:300]))
print(f"     endless loop refused after {dt:.1f} s")

if not check.failed:
    shutil.rmtree(W, ignore_errors=True)
check.finish()
