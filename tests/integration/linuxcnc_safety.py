#!/usr/bin/env python3
"""Unsafe programs on the real controller: what LinuxCNC does with them, and what `probeloop check` does
(issue 31, item 5).

The LinuxCNC-dialect seeded unsafe programs of check_cli.py (the same edits, tests/integration/
unsafe_edits.py) of the sphere cycle `probeloop plan` emits for parts/machines/linuxcnc_rotary_mill.yaml
are run, with the unedited program as the control, on LinuxCNC 2.9 in simulation (tools/linuxcnc_sim: one
LinuxCNC start, the programs run in turn by the headless display, the machine brought back after an error);
one more than check_cli.py: an overflowing product (1e200 in a parameter, squared) on a line short enough
for LinuxCNC's interpreter, which refuses overflowing_coordinate's 317 characters as too long.
Recorded per program: LinuxCNC's error messages (refused at a line, e.g. a soft limit), whether it ran to its
end, the probe contacts, and every intrusion of the stylus-tip ball into the virtual sphere during a move
that is not a probing move (sphere_probe.py: motion.motion-type != 5): a collision the controller did not see.

LinuxCNC runs a shortened form of each edited program, so that all of them take about a minute: the same
lines up to the end of the edited move's point (the first retract to the clearance plane at or after the
verifier's finding), then the cycle's end (tool-change height, probe out, LOGCLOSE, M2); one cycle
instead of 12 (no G4 P300 between cycles); and the start where every cycle but the first starts (above the
last sphere, X-160 Y0 at the tool-change height, two header comments replaced by the two G53 moves). Line
numbers are those of the full edited program up to the cut. `probeloop check` must refuse the full edited
program exactly as check_cli.py asserts (rule at line, nothing unexplained; exit 2 naming the line for a
coordinate that is not a number) and the shortened one with the same finding; the control passes both
ways and runs on LinuxCNC to its end with one contact and no intrusion. What LinuxCNC does is asserted as
measured (the table in docs/linuxcnc.md, "Unsafe programs on the controller"), so a change of either side
shows. No LinuxCNC process may be left afterwards.

Exit 77 (ctest SKIP_RETURN_CODE) without LinuxCNC, /usr/bin/python3 with hal and linuxcnc, or PyYAML.
Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR. LC_SAFETY_KEEP=1 keeps the work folder."""
import json
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
import unsafe_edits as ue  # noqa: E402
from linuxcnc_common import SRC, SYS_PY, TOOLS, finish_run, skip_without_linuxcnc  # noqa: E402

PL = os.environ["PROBELOOP"]
MACHINE = os.path.join(SRC, "parts", "machines", "linuxcnc_rotary_mill.yaml")
PART = os.path.join(SRC, "parts", "sphere_artifact.yaml")
MOTION_TYPES = {0: "idle", 1: "rapid", 2: "feed", 3: "arc", 4: "tool change", 5: "probing", 6: "indexing"}


skip_without_linuxcnc("linuxcnc_safety")

# What LinuxCNC does with each program, as measured (docs/linuxcnc.md): ran = it ran to its end without an
# error message; error = a regex its error message(s) must match (None: none); intrusion = the stylus tip went
# into the sphere during a non-probing move.
EXPECT = {
    "off_travel": {"ran": False, "error": r"would exceed Z's positive limit", "intrusion": False},
    "rapid_through_sphere": {"ran": False, "error": r"^Probe tripped during non-probe move", "intrusion": True},
    "no_contact_check": {"ran": True, "error": None, "intrusion": False},
    "unprotected_descent": {"ran": True, "error": None, "intrusion": False},
    "c_below_clearance": {"ran": True, "error": None, "intrusion": False},
    "spindle_with_probe": {"ran": True, "error": None, "intrusion": False},
    "nan_then_rapid_into_sphere": {"ran": False, "error": r"^Calculation resulted in 'infinity'", "intrusion": False},
    "overflowing_coordinate": {"ran": False, "error": r"^Command too long", "intrusion": False},
    "overflow_in_parameter": {"ran": False, "error": r"^Calculation resulted in 'infinity'", "intrusion": False},
    "rapid_only": {"ran": False, "error": r"^Probe tripped during non-probe move", "intrusion": True},
}


def pl(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def findings(stdout):
    return [(m.group(2), int(m.group(1))) for m in re.finditer(r"^\S+?:(\d+): ([a-z-]+): ", stdout, re.M)]


def shortened(lines, finding_line, start_xy):
    """The form LinuxCNC runs (see the docstring); line numbers kept up to the cut."""
    lines = list(lines)
    cut = ue.first(lines, r"G0 Z113\.0000", finding_line - 1)
    heads = [i for i, t in enumerate(lines) if t.startswith("(position ")]
    here = max([i for i in heads if i < finding_line - 1], default=heads[0])
    if here > heads[0]:   # the positions before the finding's: blank lines; the tip starts above their last sphere
        xy = [m.groups() for m in (re.match(r"G0 X(\S+) Y(\S+)$", t) for t in lines[heads[0]:here]) if m][-1]
        assert tuple(xy) == tuple(start_xy), (xy, start_xy)
        lines[heads[0]:here] = [""] * (here - heads[0])
    end = max(i for i, t in enumerate(lines) if t == "G53 G0 Z500.0000")   # the cycle's end
    assert end > cut, (end, cut)
    w = ue.first(lines, r"o100 while \[#<_pl_cycle> LE 12\]")
    lines[w] = lines[w].replace("LE 12]", "LE 1]")
    g = ue.first(lines, r"o101 if \[#<_pl_cycle> LT 12\]")
    lines[g] = lines[g].replace("LT 12]", "LT 1]")
    assert lines[1].startswith("(") and lines[2].startswith("("), lines[1:3]
    lines[1], lines[2] = "G53 G0 Z500.0000", f"G53 G0 X{start_xy[0]} Y{start_xy[1]} C0"
    return lines[:cut + 1] + lines[end:]


check = Checks()
work = tempfile.mkdtemp(prefix="probeloop-lcsafety-")
os.chmod(work, 0o755)
t0 = time.monotonic()
rows = []
try:
    code, o, e = pl("plan", PART, "--machine", MACHINE, "--dialect", "linuxcnc", "--out", f"{work}/plan")
    if code != 0:
        check("probeloop plan of the sphere artifact on the LinuxCNC machine", False, e)
        raise SystemExit(check.finish())
    base = open(f"{work}/plan/sphere_cycle.ngc").read().split("\n")
    end = max(i for i, t in enumerate(base) if t == "G53 G0 Z500.0000")
    m = [re.match(r"G0 X(\S+) Y(\S+)$", t) for t in base[:end]]
    start_xy = [x for x in m if x][-1].groups()   # where a cycle leaves the tip: above the last sphere

    # (name, edited lines, what check must report: ("rule", line, allowed) or ("nonfinite", line, text))
    cases = [("unedited", list(base), None)]
    for name, dialect, edit in ue.SPHERE_CASES:
        if dialect == "linuxcnc":
            lines, expect, allowed = edit(list(base))
            cases.append((name, lines, ("rule", expect, allowed)))
    lines, expect, allowed = ue.spindle_with_probe(list(base))   # check_cli edits the Fanuc program; here ours
    cases.append(("spindle_with_probe", lines, ("rule", expect, allowed)))
    for name, dialect, after, insert, bad, text in ue.NONFINITE:
        if dialect == "linuxcnc":
            lines, i = ue.insert_after(list(base), after, insert)
            cases.append((name, lines, ("nonfinite", i + 1 + bad, text)))
    # Not in check_cli.py: an overflowing product on a line LinuxCNC accepts (overflowing_coordinate's
    # line is too long for LinuxCNC's interpreter): 1e200 in a parameter, squared.
    lines, i = ue.insert_after(list(base), "G43 H99", ["#901 = 1" + "0" * 200, "G0 Z[#901 * #901]"])
    cases.append(("overflow_in_parameter", lines, ("nonfinite", i + 3, "a product in")))
    lines, i = ue.rapid_only(list(base))
    cases.append(("rapid_only", lines, ("rapid_only", i + 2, None)))

    cfg = f"{work}/lcnc"
    r = subprocess.run([SYS_PY, os.path.join(TOOLS, "make_config.py"), "--machine", MACHINE, "--manifest",
                        f"{work}/plan/plan.json", "--truth", os.path.join(SRC, "examples", "truth_rigid.yaml"),
                        "--out", cfg], capture_output=True, text=True)
    check("make_config.py wrote the configuration", r.returncode == 0, r.stdout + r.stderr)
    programs = []
    for name, lines, want in cases:
        full = f"{work}/{name}.ngc"
        open(full, "w").write("\n".join(lines))
        code, o, e = pl("check", full, "--machine", MACHINE, "--part", PART)
        got = findings(o)
        row = {"name": name, "check_rc": code, "check": got, "check_err": e.strip().splitlines()[:1]}
        if want is None:
            check(f"{name}: probeloop check passes it (exit 0)", code == 0 and not got, o + e)
            finding_line = ue.first(lines, r"\(LOG,PT") + 1
        elif want[0] == "rule":
            expect, allowed = want[1], want[2]
            check(f"{name}: probeloop check refuses it: {expect[0]} at line {expect[1]} (exit 3)",
                  code == 3 and expect in got and set(got) <= {expect} | allowed, o + e)
            finding_line = expect[1]
        elif want[0] == "nonfinite":
            finding_line, text = want[1], want[2]
            check(f"{name}: probeloop check refuses it: exit 2 at line {finding_line} ({text})",
                  code == 2 and f"{name}.ngc:{finding_line}: {text}" in e and "not a finite number" in e
                  and "safe" not in o, (code, o[:300], e[:600]))
        else:   # the rapid alone: check_cli asserts a finding; here the collision at the rapid itself
            finding_line = want[1]
            check(f"{name}: probeloop check refuses it: collision at line {finding_line} (exit 3)",
                  code == 3 and ("collision", finding_line) in got, o + e)
        row["finding_line"] = finding_line
        short = shortened(lines, finding_line, start_xy)
        path = f"{work}/short/{name}.ngc"
        os.makedirs(os.path.dirname(path), exist_ok=True)
        open(path, "w").write("\n".join(short))
        code2, o2, e2 = pl("check", path, "--machine", MACHINE, "--part", PART)
        if want is None:
            check(f"{name}: the shortened form LinuxCNC runs passes too", code2 == 0, o2 + e2)
        elif want[0] == "nonfinite":
            check(f"{name}: the shortened form is refused the same way (exit 2, line {finding_line})",
                  code2 == 2 and f"{name}.ngc:{finding_line}: " in e2, e2[:600])
        else:
            rule = want[1][0] if want[0] == "rule" else "collision"
            check(f"{name}: the shortened form is refused with the same finding ({rule} at line {finding_line})",
                  code2 == 3 and (rule, finding_line) in findings(o2), o2 + e2)
        rows.append(row)
        if name != "unedited":   # no_contact_check runs the same motion on LinuxCNC (its o-if is a no-op without contact)
            programs.append(path)

    # One LinuxCNC session for all programs (run_program.py stops everything, also on errors).
    sys.path.insert(0, TOOLS)
    import run_program  # noqa: E402
    t_lc = time.monotonic()
    try:
        _, result = run_program.run(cfg, programs, timeout=120, quiet=True)
    except RuntimeError as ex:   # processes were left (and killed)
        check("run_program.py: nothing left after the session", False, str(ex))
        result = json.load(open(f"{cfg}/result.json")) if os.path.exists(f"{cfg}/result.json") else {}
    lc_s = time.monotonic() - t_lc
    runs = result.get("programs", [])
    check(f"LinuxCNC ran the session: {len(programs)} programs", len(runs) == len(programs),
          json.dumps(result.get("messages"))[:1500])
    events = [json.loads(x) for x in open(f"{cfg}/contacts.jsonl")] if os.path.exists(f"{cfg}/contacts.jsonl") else []
    for row, run in zip([r for r in rows if r["name"] != "unedited"], runs):
        name = row["name"]
        inwin = [ev for ev in events if run["t_start"] <= ev.get("t", -1) <= run["t_end"]]
        errors = [msg["text"] for msg in run["messages"] if msg["kind"] == "error"
                  and not msg["text"].startswith("headless_display: error while waiting")]
        intr = [ev for ev in inwin if ev["event"] == "intrusion" and set(ev["motion_types"]) - {5}]
        contacts = [ev for ev in inwin if ev["event"] == "contact"]
        row.update(ran=run["ok"], errors=errors, intrusions=intr, contacts=len(contacts),
                   contacts_not_probing=sum(1 for c in contacts if c.get("motion_type") != 5), run_s=run["t_end"] - run["t_start"])
        exp = EXPECT[name]
        if exp["ran"]:
            check(f"{name}: LinuxCNC runs it to its end, no error message", run["ok"] and not errors, errors)
        else:
            check(f"{name}: LinuxCNC stops it with an error", not run["ok"] and errors, errors)
        if exp["error"]:
            check(f"{name}: LinuxCNC's message matches /{exp['error']}/", any(re.search(exp["error"], t) for t in errors),
                  errors)
            lines_named = [int(x) for t in errors for x in re.findall(r"line (\d+)", t)]
            if lines_named:
                check(f"{name}: probeloop check refuses at the line LinuxCNC stops at ({min(lines_named)}) or before",
                      row["finding_line"] <= min(lines_named), (row["finding_line"], errors))
        if exp["intrusion"]:
            check(f"{name}: the stylus tip went more than 0.5 mm into the sphere during a rapid",
                  intr and max(ev["depth_mm"] for ev in intr) > 0.5 and all(1 in ev["motion_types"] for ev in intr),
                  intr or inwin)
        else:
            check(f"{name}: no intrusion into the sphere", not intr, intr)
        if name in ("no_contact_check", "unprotected_descent", "c_below_clearance"):   # one point each, as emitted
            check(f"{name}: exactly one contact, during the probing move (G38.2)", len(contacts) == 1
                  and row["contacts_not_probing"] == 0, contacts)

    print("\n   program                      | probeloop check                  | LinuxCNC")
    for row in rows:
        chk = ("passes" if row["check_rc"] == 0 else
               f"exit {row['check_rc']}: " + (", ".join(f"{r}@{ln}" for r, ln in row["check"]) or
                                              f"not a finite number@{row['finding_line']}"))
        if "ran" not in row:
            lc = "not run"
        else:
            lc = "ran to its end" if row["ran"] else "stopped: " + "; ".join(row["errors"])[:110]
            for ev in row["intrusions"]:
                kinds = "/".join(MOTION_TYPES.get(k, str(k)) for k in ev["motion_types"] if k != 0)
                lc += f"; tip {ev['depth_mm']:.1f} mm into the sphere in a {kinds} move"
            lc += f"; {row['contacts']} contact(s)"
            if row["contacts_not_probing"]:
                lc += f" ({row['contacts_not_probing']} not while probing)"
            lc += f" [{row['run_s'] or 0:.1f} s]"
        print(f"   {row['name']:<28} | {chk:<32} | {lc}")
    json.dump(rows, open(f"{work}/table.json", "w"), indent=1)
    print(f"   LinuxCNC session {lc_s:.0f} s")
finally:
    finish_run(check, work, t0, keep=os.environ.get("LC_SAFETY_KEEP") == "1")
check.finish()
