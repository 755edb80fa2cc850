#!/usr/bin/env python3
"""Compare LinuxCNC rs274's canonical output of the stepped workpiece's three programs with plan.json.

Independent of the planner's code: the geometry and the clock come from rs274's canonical
calls, the machine description and (with --part) the piece's description; the manifest is
only what is checked.

rs274 (standalone, Debian linuxcnc-uspace) prints canonical positions in program units (mm
after G21) to 4 decimals, as X Y Z A B C of the controlled point without the tool length and
the work offsets: machine gauge line = canonical + G5x + G92 offsets + tool length offset
(USE_TOOL_LENGTH_OFFSET, whose Z is the table's length; with the inch tool table 140 mm prints
as 140.0000). A G53 move prints the same way (G53 G0 Z550 with T1 of 140 mm active prints Z
410), G4 P1800 prints DWELL(1800.0000), T1 M6 prints SELECT_TOOL, START_CHANGE, CHANGE_TOOL(1)
and G43 H1 USE_TOOL_LENGTH_OFFSET(0 0 140, ...). Standalone, a G38.x move never trips: the
probed position (#5061-#5063, in the LOG line) is the move's target.

Every program starts in rs274 at canonical (0, 0, 0) and prints 0 for an axis it has not moved
yet; on the machine, programs run back to back and an axis stays where the previous program
left it (the first program starts with the gauge line at the top of the Z travel over the C
axis, or X = Y = 0 without one, clamped into the travel: docs/simulator.md §2). So an axis
counts as the machine's carried-over value until its canonical value first changes within the
program (a program whose first move of an axis goes to exactly 0 would be misread: the
planner's programs move Z first with G53 and X/Y to the part).

Checks:
  every program: reaches PROGRAM_END, no ABORT reached, no interpreter error, no arc, no
    inverse-time feed, no XY rotation;
  finishing (and roughing, if the manifest lists cuts of it): every cut of the manifest, in
    the manifest's order, is a run of STRAIGHT_FEEDs that leaves from_mm and arrives at to_mm
    (one feed for a straight cut; a closed contour when from = to), with no traverse inside and
    Z constant (1e-4 mm) = the planned Z; the four walls S<k>_XP/XN/YP/YN of every step are
    cut at that step's floor depth (the Z of its floor cuts S<k>_F-*, and with --part the top's
    Z minus the step's floor_depth), at the step's feed_xy with the spindle at its speed;
    every wall cut runs at the tool's radius from its nominal face; with --compensation (the
    file given to plan --compensate) the walls move in by wall_um and the floors up by
    floor_um (each rounded to the programs' 0.1 um);
  probing: every STRAIGHT_PROBE is either a measuring move (a LOG follows) whose target is
    the planned overtravel end on the approach line (contact + overtravel * approach), or a
    protected move ending at the next point's start (contact - approach_mm * approach); every
    measuring move starts there; one LOG per manifest point in order with 'PT 1 <position>
    <point> x y z';
  timing: each program re-timed from the canonical stream with the simulator's clock
    (docs/simulator.md §2, no acceleration): a STRAIGHT_TRAVERSE moves every axis at
    rapid_feed and takes the slowest axis's time (B, C at their max_speed); a STRAIGHT_FEED
    takes its XYZ path length / the current SET_FEED_RATE (C alone: degrees / F); DWELL its
    seconds; CHANGE_TOOL tool_change.time; a protected STRAIGHT_PROBE its full length / F; a
    measuring one is timed from its start to the manifest point's contact_mm (the nominal
    contact, where the controller latches and stops: the next move leaves from there). The
    comparison with the manifest: each program's duration_s; each cut's start_s / end_s
    (relative to its program's start_s: the time the tool leaves from_mm and arrives at to_mm,
    so a floor contour S<k>_F-<j> (from = to) spans all its sides, not only the last); each
    feature's cut_time_s (the middle from its first cut's start to its last cut's end);
    each step's start_s / end_s (the first and last STRAIGHT_FEED at or below the top face
    between the warm-up dwells: the plunge or the first top lane to the last wall) and
    temp_state_min (the mid-time of its four wall cuts from step 1's start, min); each point's
    time_in_cycle_s (the end of its measuring move from the probing program's start); the
    first program at 0; the warm-up: one DWELL between consecutive steps, the spindle turning
    at the next step's speed, with --part each = procedure.warm_up.spindle_idle; the
    machine-off waits (start_s differences minus durations) = with --part
    procedure.machine_off_before and machine_off_before_probing. Tolerance --tol-s (1 ms
    default: the coordinates are the planner's as written, so only float rounding differs).

Usage: check_sw_rs274.py plan.json CANON_ROUGHING CANON_FINISHING CANON_PROBING
         --approach MM --overtravel MM --machine MACHINE.yaml [--part DESCRIPTION.yaml]
"""
import argparse
import json
import math
import re
import sys

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("plan", help="plan.json of the stepped workpiece")
ap.add_argument("canons", nargs=3, metavar="CANON", help="rs274 output of roughing, finishing, probing")
ap.add_argument("--approach", type=float, required=True, metavar="MM", help="probing.approach of the description")
ap.add_argument("--overtravel", type=float, required=True, metavar="MM", help="probing.overtravel of the description")
ap.add_argument("--machine", required=True, metavar="YAML", help="the machine description the plan was made for")
ap.add_argument("--part", metavar="YAML", help="the stepped-workpiece description (procedure waits, floor depths)")
ap.add_argument("--compensation", metavar="JSON", help="the compensation.json the plan was made with (plan --compensate)")
ap.add_argument("--tol-s", type=float, default=1e-3, metavar="S", help="time tolerance, s (default 0.001)")
args = ap.parse_args()
for name in ("approach", "overtravel"):
    if not getattr(args, name) > 0:
        ap.error(f"--{name} must be a positive distance in mm (got {getattr(args, name)})")

TOL = 6e-5  # rs274 prints 4 decimals; the plan's program coordinates are rounded to 4 as written
CTOL = 6e-4  # C is written with 3 decimals
ZTOL = 1e-4
TTOL = args.tol_s
errors = []


# --- a small reader for the YAML subset of the shipped descriptions ---------------------------
# Block maps and lists by indentation, flow maps / lists ({a: 1, b: [2, 3]}), plain or quoted
# scalars, comments; a flow collection may continue on the following lines.
def _strip_comment(line):
    out, quote = [], None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'" and (i == 0 or line[i - 1] in " \t:[{,"):
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1] in " \t"):
            break
        out.append(ch)
    return "".join(out).rstrip()


def _flow(text):
    pos = 0

    def ws():
        nonlocal pos
        while pos < len(text) and text[pos] in " \t\n":
            pos += 1

    def scalar(stops):
        nonlocal pos
        ws()
        if pos < len(text) and text[pos] in "\"'":
            q = text[pos]
            end = text.index(q, pos + 1)
            s = text[pos + 1:end]
            pos = end + 1
            return s
        start = pos
        while pos < len(text) and text[pos] not in stops:
            if text[pos] == ":" and (pos + 1 == len(text) or text[pos + 1] in " \t") and ":" in stops:
                break
            pos += 1
        return text[start:pos].strip()

    def value(stops):
        nonlocal pos
        ws()
        if pos < len(text) and text[pos] == "{":
            pos += 1
            d = {}
            while True:
                ws()
                if text[pos] == "}":
                    pos += 1
                    return d
                k = scalar(":,}")
                if text[pos] != ":":
                    raise ValueError(f"expected ':' in {text!r}")
                pos += 1
                d[k] = value(",}")
                ws()
                if text[pos] == ",":
                    pos += 1
        if pos < len(text) and text[pos] == "[":
            pos += 1
            lst = []
            while True:
                ws()
                if text[pos] == "]":
                    pos += 1
                    return lst
                lst.append(value(",]"))
                ws()
                if text[pos] == ",":
                    pos += 1
        return scalar(stops)

    v = value("")
    return v


def load_yaml(path):
    raw = [_strip_comment(l) for l in open(path, encoding="utf-8").read().splitlines()]
    lines, buf, depth = [], "", 0
    for l in raw:
        if not l.strip() and not buf:
            continue
        buf = buf + " " + l.strip() if buf else l
        depth = sum(buf.count(c) for c in "{[") - sum(buf.count(c) for c in "}]")
        if depth <= 0:
            lines.append((len(buf) - len(buf.lstrip()), buf.strip()))
            buf = ""
    pos = 0

    def block(indent):
        nonlocal pos
        if pos < len(lines) and lines[pos][1].startswith("- "):
            out = []
            while pos < len(lines) and lines[pos][0] == indent and lines[pos][1].startswith("- "):
                rest = lines[pos][1][2:].strip()
                if re.match(r"^[\w.]+:(\s|$)", rest):  # "- key: value" opens a map in the list
                    lines[pos] = (indent + 2, rest)
                    out.append(block(indent + 2))
                else:
                    out.append(_flow(rest))
                    pos += 1
            return out
        out = {}
        while pos < len(lines) and lines[pos][0] == indent and not lines[pos][1].startswith("- "):
            m = re.match(r"^([^:]+):(?:\s+(.*))?$", lines[pos][1])
            if not m:
                raise ValueError(f"{path}: cannot read line {lines[pos][1]!r}")
            key, rest = m.group(1).strip(), (m.group(2) or "").strip()
            pos += 1
            if rest:
                out[key] = _flow(rest)
            elif pos < len(lines) and (lines[pos][0] > indent or (lines[pos][0] == indent and lines[pos][1].startswith("- "))):
                out[key] = block(lines[pos][0])
            else:
                out[key] = None
        return out

    return block(0)


UNITS = {
    "length": {"mm": 1.0, "m": 1000.0, "cm": 10.0, "um": 1e-3, "µm": 1e-3, "in": 25.4},
    "feed": {"mm/min": 1.0, "m/min": 1000.0, "mm/s": 60.0, "in/min": 25.4},
    "duration": {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0, "ms": 1e-3},
    "rotspeed": {"rpm": 1.0, "1/min": 1.0, "deg/s": 1.0 / 6.0},
}


def quantity(v, dim, where):
    m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S*)\s*", str(v))
    if not m or (m.group(2) and m.group(2) not in UNITS[dim]):
        sys.exit(f"check_sw_rs274.py: {where}: cannot read '{v}' as a {dim}")
    return float(m.group(1)) * (UNITS[dim][m.group(2)] if m.group(2) else 1.0)


def get(d, path, what):
    cur = d
    for k in path.split("."):
        if not isinstance(cur, dict) or k not in cur:
            sys.exit(f"check_sw_rs274.py: {what}: no key '{path}'")
        cur = cur[k]
    return cur


mach = load_yaml(args.machine)
RAPID = quantity(get(mach, "rapid_feed", args.machine), "feed", "rapid_feed")
TC_TIME = quantity(get(mach, "tool_change.time", args.machine), "duration", "tool_change.time")
axes = get(mach, "axes", args.machine)
travel = {a: (quantity(axes[a]["min"], "length", f"axes.{a}.min"), quantity(axes[a]["max"], "length", f"axes.{a}.max"))
          for a in "XYZ"}
rot_speed = {a: quantity(axes[a]["max_speed"], "rotspeed", f"axes.{a}.max_speed") for a in ("B", "C") if a in axes}
centre = [0.0, 0.0]
if "C" in axes:
    centre = [quantity(get(mach, "c_axis.centre_x", args.machine), "length", "c_axis.centre_x"),
              quantity(get(mach, "c_axis.centre_y", args.machine), "length", "c_axis.centre_y")]
# The machine at rest before the first program (docs/simulator.md §2): gauge line at the top of
# Z over the C axis (X = Y = 0 without one), clamped into the travel.
START = [min(max(centre[0], travel["X"][0]), travel["X"][1]), min(max(centre[1], travel["Y"][0]), travel["Y"][1]),
         travel["Z"][1]]

desc = None
if args.part:
    desc = load_yaml(args.part)
    OFF_BEFORE = quantity(get(desc, "procedure.machine_off_before", args.part), "duration", "procedure.machine_off_before")
    OFF_PROBING = quantity(get(desc, "procedure.machine_off_before_probing", args.part), "duration",
                           "procedure.machine_off_before_probing")
    IDLE = quantity(get(desc, "procedure.warm_up.spindle_idle", args.part), "duration", "procedure.warm_up.spindle_idle")
    FLOOR = [quantity(s["floor_depth"], "length", "steps[].floor_depth") for s in get(desc, "steps", args.part)]

plan = json.load(open(args.plan))
COMP = json.load(open(args.compensation)) if args.compensation else None


def comp_mm(step, key):
    """The compensation of step `step` (wall side XP/XN/YP/YN or floor_um), mm, rounded as the
    programs are written (0.1 um)."""
    if COMP is None:
        return 0.0
    s = COMP["steps"][step - 1]
    um = s["floor_um"] if key == "floor_um" else s["wall_um"][key]
    return math.copysign(math.floor(abs(um) * 10 + 0.5), um) / 1e4  # half away from zero, as the planner
roles = [p.get("role") for p in plan["programs"]]
if roles != ["roughing", "finishing", "probing"]:
    sys.exit(f"check_sw_rs274.py: the manifest's programs are {roles}, expected roughing, finishing, probing")
if plan.get("kind") != "stepped_workpiece" or "stepped_workpiece" not in plan:
    sys.exit("check_sw_rs274.py: not a stepped-workpiece manifest (kind / stepped_workpiece missing)")
sw = plan["stepped_workpiece"]
points = plan["points"]

# --- canonical stream --------------------------------------------------------------------------
NUM = r"(-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"
MOTION = re.compile(r"\b(STRAIGHT_TRAVERSE|STRAIGHT_FEED|STRAIGHT_PROBE)\(" + ", ".join([NUM] * 6) + r"\)")
CALLS = [
    ("FEEDRATE", re.compile(r"\bSET_FEED_RATE\(" + NUM + r"\)")),
    ("DWELL", re.compile(r"\bDWELL\(" + NUM + r"\)")),
    ("CHANGE_TOOL", re.compile(r"\bCHANGE_TOOL\((\d+)\)")),
    ("TLO", re.compile(r"\bUSE_TOOL_LENGTH_OFFSET\(" + NUM + " " + NUM + " " + NUM + ",")),
    ("G5X", re.compile(r"\bSET_G5X_OFFSET\((\d+), " + ", ".join([NUM] * 6) + r"\)")),
    ("G92", re.compile(r"\bSET_G92_OFFSET\(" + ", ".join([NUM] * 6) + r"\)")),
    ("SPEED", re.compile(r"\bSET_SPINDLE_SPEED\(\d+, " + NUM + r"\)")),
    ("SPINDLE_ON", re.compile(r"\bSTART_SPINDLE_(?:CLOCKWISE|COUNTERCLOCKWISE)\(")),
    ("SPINDLE_OFF", re.compile(r"\bSTOP_SPINDLE_TURNING\(")),
    ("ROTATION", re.compile(r"\bSET_XY_ROTATION\(" + NUM + r"\)")),
    ("FEED_MODE", re.compile(r"\bSET_FEED_MODE\(\d+, (\d+)\)")),
    ("ARC", re.compile(r"\bARC_FEED\(")),
    ("END", re.compile(r"\bPROGRAM_END\(")),
]
LOG = re.compile(r'LOG\("PT ([^"]*)"\)')


def events(path, name):
    """The canonical calls in order: (kind, value, line number)."""
    text = open(path, errors="replace").read()
    if "PROGRAM_END" not in text:
        errors.append(f"{name}: rs274 did not reach PROGRAM_END")
    if "ABORT" in text:
        errors.append(f"{name}: an ABORT was reached")
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if re.search(r"\berror\b|near line", line, re.IGNORECASE) and "COMMENT" not in line:
            errors.append(f"{name}: interpreter error: {line.strip()}")
        if "COMMENT(" in line:
            continue
        m = MOTION.search(line)
        if m:
            out.append((m.group(1), tuple(float(v) for v in m.groups()[1:]), n))
            continue
        m = LOG.search(line)
        if m:
            out.append(("LOG", m.group(1), n))
            continue
        for kind, rx in CALLS:
            m = rx.search(line)
            if m:
                out.append((kind, tuple(m.groups()), n))
                break
    return out


class Motion:
    __slots__ = ("kind", "ev", "line", "start", "end", "t0", "t1", "F", "spindle", "measuring", "point")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))


def close(p, q, tol=TOL):
    return all(abs(a - b) <= tol for a, b in zip(p, q))


def retime(ev, name, gauge, point_iter):
    """Re-time one program from the machine state `gauge` [x, y, z, b, c] (the previous
    program's end). Returns (duration, motions, dwells, end gauge). A motion's start / end are
    machine tip coordinates (canonical + work offsets: what the manifest's from/to and
    contacts are) and C."""
    t = 0.0
    g5x = [0.0] * 6
    g92 = [0.0] * 6
    tlo = [0.0, 0.0, 0.0]
    F = None
    speed, spindle = 0.0, False
    printed = [0.0] * 6  # rs274's canonical position at the program's start
    known = [False] * 6
    motions, dwells = [], []
    g = list(gauge)  # x, y, z (gauge line) and a, b, c
    for i, (kind, v, line) in enumerate(ev):
        where = f"{name} line {line}"
        if kind == "FEEDRATE":
            F = float(v[0])
        elif kind == "DWELL":
            dwells.append((t, float(v[0]), spindle, speed, i))
            t += float(v[0])
        elif kind == "CHANGE_TOOL":
            t += TC_TIME
        elif kind == "TLO":
            tlo = [float(x) for x in v]
        elif kind == "G5X":
            g5x = [float(x) for x in v[1:]]
        elif kind == "G92":
            g92 = [float(x) for x in v]
        elif kind == "SPEED":
            speed = float(v[0])
        elif kind == "SPINDLE_ON":
            spindle = True
        elif kind == "SPINDLE_OFF":
            spindle = False
        elif kind == "ROTATION" and abs(float(v[0])) > 1e-9:
            errors.append(f"{where}: XY rotation {v[0]} (the programs must not rotate the work offset)")
        elif kind == "FEED_MODE" and v[0] != "0":
            errors.append(f"{where}: feed mode {v[0]} (expected units per minute, G94)")
        elif kind == "ARC":
            errors.append(f"{where}: an ARC_FEED (the planner writes straight moves only)")
        elif kind in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE"):
            new = list(g)
            for a in range(6):
                if not known[a] and abs(v[a] - printed[a]) < 1e-12:
                    continue  # not moved yet in this program: where the previous program left it
                known[a] = True
                off = g5x[a] + g92[a] + (tlo[a] if a < 3 else 0.0)
                new[a] = v[a] + off
            printed = list(v)
            tip0 = (g[0] - tlo[0], g[1] - tlo[1], g[2] - tlo[2], g[3], g[4], g[5])
            d = [new[a] - g[a] for a in range(3)]
            dist = math.sqrt(sum(x * x for x in d))
            measuring, point = False, None
            if kind == "STRAIGHT_TRAVERSE":
                dt = max(abs(x) for x in d) / RAPID * 60.0
                for a, ax in ((4, "B"), (5, "C")):
                    if abs(new[a] - g[a]) > 1e-9:
                        if ax not in rot_speed:
                            errors.append(f"{where}: a move of {ax} on a machine without it")
                        else:
                            dt = max(dt, abs(new[a] - g[a]) / (rot_speed[ax] * 360.0) * 60.0)
            else:
                if not F or F <= 0:
                    errors.append(f"{where}: a {kind} without a feed rate")
                    F = float("inf")
                if kind == "STRAIGHT_FEED" and dist < 1e-12 and abs(new[5] - g[5]) > 1e-9:
                    dt = abs(new[5] - g[5]) / F * 60.0  # C alone (F in deg/min)
                else:
                    dt = dist / F * 60.0
                if kind == "STRAIGHT_PROBE":
                    nxt = next((e for e in ev[i + 1:] if e[0] in ("LOG", "STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE")), None)
                    measuring = nxt is not None and nxt[0] == "LOG"
                    if measuring:
                        point = next(point_iter, None)
                        if point is None:
                            errors.append(f"{where}: a measuring move after the last planned point")
                        else:
                            # Timed to the nominal contact, where the controller latches and stops.
                            c = point["contact_mm"]
                            new[:3] = [c[0] + tlo[0], c[1] + tlo[1], c[2] + tlo[2]]
                            dt = math.dist(new[:3], g[:3]) / F * 60.0
            tip1 = tuple(new[a] - (tlo[a] if a < 3 else 0.0) for a in range(3)) + tuple(new[3:])
            # The target as printed (machine tip coordinates), which for a measuring move is the
            # overtravel end, not where the clock leaves it.
            target = tuple(v[a] + g5x[a] + g92[a] for a in range(6))
            motions.append(Motion(kind=kind, ev=i, line=line, start=tip0, end=tip1 if not measuring else target,
                                  t0=t, t1=t + dt, F=F, spindle=(spindle, speed), measuring=measuring, point=point))
            t += dt
            g = new
    return t, motions, dwells, g


names = ["roughing", "finishing", "probing"]
evs = [events(c, n) for c, n in zip(args.canons, names)]
gauge = START + [0.0, 0.0, 0.0]
gauge = [gauge[0], gauge[1], gauge[2], 0.0, 0.0, 0.0]
runs = {}
pit = iter(points)
for n, ev in zip(names, evs):
    dur, mo, dw, gauge = retime(ev, n, gauge, pit if n == "probing" else iter(()))
    runs[n] = (dur, mo, dw)
prog = {p["role"]: p for p in plan["programs"]}
worst = {n: 0.0 for n in names}


def cmp_time(program, what, mine, planned, scale=1.0, unit="s"):
    """Compare a time (relative values in s, or scaled e.g. to min); record the worst."""
    d = abs(mine - planned) * (60.0 if unit == "min" else 1.0)
    worst[program] = max(worst[program], d)
    if not d <= TTOL:
        errors.append(f"{program}: {what}: rs274 timing {mine:.4f} {unit}, manifest {planned:.4f} {unit} "
                      f"(differs by {d:.4f} s)")


# --- programs: durations and the waits between them ---------------------------------------------
for n in names:
    cmp_time(n, "duration_s", runs[n][0], prog[n]["duration_s"])
if abs(prog["roughing"]["start_s"]) > TTOL:
    errors.append(f"roughing: start_s {prog['roughing']['start_s']} (the plan's clock starts at 0 with roughing)")
waits = []
for a, b, key in (("roughing", "finishing", "machine_off_before"), ("finishing", "probing", "machine_off_before_probing")):
    wait = prog[b]["start_s"] - prog[a]["start_s"] - runs[a][0]
    waits.append(wait)
    if desc is not None:
        want = OFF_BEFORE if key == "machine_off_before" else OFF_PROBING
        worst[b] = max(worst[b], abs(wait - want))
        if abs(wait - want) > TTOL:
            errors.append(f"{b}: starts {wait:.4f} s after {a} ends (rs274 timing), the description's procedure.{key} is {want:.4f} s")

# --- cuts ---------------------------------------------------------------------------------------
cut_times = {}  # cut id -> (t0, t1, z, motions) relative to its program


def check_cuts(role):
    cuts = [c for c in plan["cuts"] if c["program"] == role]
    if role == "finishing" and not cuts:
        errors.append("finishing: the manifest lists no cut of program role 'finishing'")
    motions = runs[role][1]
    j = 0
    for cut in cuts:
        frm, to = cut["from_mm"], cut["to_mm"]
        where = f"{role}: cut {cut['id']} (feature {cut['feature']}, step {cut['cycle']})"
        first = next((k for k in range(j, len(motions)) if motions[k].kind == "STRAIGHT_FEED" and close(motions[k].start[:3], frm)
                      and not close(motions[k].end[:3], motions[k].start[:3])), None)
        if first is None:
            errors.append(f"{where}: no STRAIGHT_FEED leaves {frm} after the previous cut (planned order)")
            return
        last = next((k for k in range(first, len(motions)) if motions[k].kind == "STRAIGHT_FEED" and close(motions[k].end[:3], to)), None)
        if last is None:
            errors.append(f"{where}: no STRAIGHT_FEED arrives at {to} after leaving {frm}")
            return
        run = motions[first:last + 1]
        if any(m.kind != "STRAIGHT_FEED" for m in run):
            errors.append(f"{where}: a {next(m.kind for m in run if m.kind != 'STRAIGHT_FEED')} between leaving {frm} "
                          f"and arriving at {to}")
        zs = [m.start[2] for m in run] + [m.end[2] for m in run]
        if max(zs) - min(zs) > ZTOL or abs(zs[0] - frm[2]) > TOL or abs(zs[0] - to[2]) > TOL:
            errors.append(f"{where}: Z from {min(zs)} to {max(zs)} over the cut, planned Z {frm[2]} -> {to[2]}")
        if any(abs(m.end[5] - cut.get("c_deg", 0.0)) > CTOL for m in run):
            errors.append(f"{where}: cut at C {run[0].end[5]}, planned C {cut.get('c_deg', 0.0)}")
        if not all(m.spindle[0] for m in run):
            errors.append(f"{where}: a cutting feed with the spindle stopped")
        t0, t1 = run[0].t0, run[-1].t1
        cut_times[cut["id"]] = (t0, t1, zs[0], run)
        cmp_time(role, f"cut {cut['id']} start_s", t0, cut["start_s"] - prog[role]["start_s"])
        cmp_time(role, f"cut {cut['id']} end_s", t1, cut["end_s"] - prog[role]["start_s"])
        j = last + 1


for role in ("roughing", "finishing"):
    check_cuts(role)
fin_cuts = [c for c in plan["cuts"] if c["program"] == "finishing"]
# A feature's cut_time_s: the middle of its cuts, from the first one's start to the last one's end.
for f in plan["features"]:
    mine = [(cut_times[c["id"]], c) for c in plan["cuts"] if c["feature"] == f["id"] and c["id"] in cut_times]
    if mine and f.get("cut_time_s") is not None:
        role = mine[0][1]["program"]
        mid = (min(t[0] for t, _ in mine) + max(t[1] for t, _ in mine)) / 2
        cmp_time(role, f"feature {f['id']} cut_time_s", mid, f["cut_time_s"] - prog[role]["start_s"])
if any(b["start_s"] < a["start_s"] for a, b in zip(fin_cuts, fin_cuts[1:])):
    errors.append("finishing: the manifest's cuts are not in the order of their start_s")

# --- steps: sections between the warm-up dwells -------------------------------------------------
fin_dur, fin_mo, fin_dw = runs["finishing"]
steps = sw.get("steps", [])
top_z = max((c["to_mm"][2] for c in fin_cuts), default=None)
tops = [c for c in fin_cuts if c["feature"] == "TOP"]
if len(fin_dw) != max(len(steps) - 1, 0):
    errors.append(f"finishing: {len(fin_dw)} DWELLs, expected one warm-up between each of the {len(steps)} steps")
for k, (t, sec, on, rpm, _) in enumerate(fin_dw):
    if desc is not None:
        worst["finishing"] = max(worst["finishing"], abs(sec - IDLE))
        if abs(sec - IDLE) > TTOL:
            errors.append(f"finishing: warm-up {k + 1}: DWELL {sec} s, the description's procedure.warm_up.spindle_idle is {IDLE} s")
    nxt = steps[k + 1] if k + 1 < len(steps) else None
    if not on or (nxt and abs(rpm - nxt["spindle_speed_rpm"]) > 0.5):
        errors.append(f"finishing: warm-up {k + 1}: spindle {'at ' + str(rpm) + ' rpm' if on else 'stopped'} during the DWELL, "
                      f"expected turning at step {k + 2}'s {nxt['spindle_speed_rpm'] if nxt else '?'} rpm")
bounds = [0.0] + [t + sec for t, sec, *_ in fin_dw] + [fin_dur + 1.0]
dwell_starts = [t for t, *_ in fin_dw] + [fin_dur + 1.0]
step_start1 = None
wall_re = re.compile(r"^S(\d+)_(XP|XN|YP|YN)$")
air_feeds = 0
for k, st in enumerate(steps if len(fin_dw) == max(len(steps) - 1, 0) else []):  # else reported above
    n = st["step"]
    lo, hi = bounds[k], dwell_starts[k]
    sec = [m for m in fin_mo if lo - 1e-9 <= m.t0 and m.t1 <= hi + 1e-9 and m.kind == "STRAIGHT_FEED"]
    at_part = [m for m in sec if top_z is not None and m.end[2] <= top_z + TOL]
    air_feeds += len(sec) - len(at_part)
    if not at_part:
        errors.append(f"finishing: step {n}: no STRAIGHT_FEED at or below the top face between the warm-ups")
        continue
    s0, s1 = at_part[0].t0, at_part[-1].t1
    if k == 0:
        step_start1 = s0
    cmp_time("finishing", f"step {n} start_s", s0, st["start_s"] - prog["finishing"]["start_s"])
    cmp_time("finishing", f"step {n} end_s", s1, st["end_s"] - prog["finishing"]["start_s"])
    walls = {wall_re.match(c["feature"]).group(2): c for c in fin_cuts
             if wall_re.match(c["feature"]) and int(wall_re.match(c["feature"]).group(1)) == n and c["cycle"] == n}
    if sorted(walls) != ["XN", "XP", "YN", "YP"]:
        errors.append(f"finishing: step {n}: wall cuts {sorted(walls)} in the manifest, expected XP, XN, YP, YN")
        continue
    if any(c["id"] not in cut_times for c in walls.values()):
        continue  # reported with the cuts
    floor_z = {round(cut_times[c["id"]][2], 4) for c in fin_cuts if c["feature"] == f"S{n}_F" and c["id"] in cut_times}
    for side, c in sorted(walls.items()):
        t0, t1, z, run = cut_times[c["id"]]
        if len(floor_z) != 1 or abs(z - next(iter(floor_z))) > TOL:
            errors.append(f"finishing: wall {c['feature']} cut at Z {z}, the floor of step {n} at Z {sorted(floor_z)}")
        if desc is not None and tops and n <= len(FLOOR):
            want = tops[0]["to_mm"][2] - FLOOR[n - 1] + comp_mm(n, "floor_um")
            if abs(z - want) > TOL:
                errors.append(f"finishing: wall {c['feature']} cut at Z {z}, the top at {tops[0]['to_mm'][2]} minus the "
                              f"description's floor_depth {FLOOR[n - 1]} of step {n} is {want}")
        # The tool's axis at its radius from the nominal face (moved in by the compensation).
        face = next((f for f in plan["features"] if f["id"] == c["feature"]), None)
        if face is not None:
            nrm, pt = face["direction"], [face["point_mm"][i] + plan["part"]["origin_mm"][i] for i in range(3)]
            want_d = sw["tool_diameter_mm"] / 2 - comp_mm(n, side)
            for m in run:
                for q in (m.start, m.end):
                    d = sum(nrm[i] * (q[i] - pt[i]) for i in range(2))
                    if abs(d - want_d) > TOL:
                        errors.append(f"finishing: wall {c['feature']} cut {d:.5f} mm from its nominal face, expected "
                                      f"{want_d:.5f} (tool radius - compensation)")
                        break
        if any(abs(m.F - st["feed_xy_mm_per_min"]) > 1e-3 for m in run):
            errors.append(f"finishing: wall {c['feature']} cut at F {run[0].F}, step {n}'s feed_xy is {st['feed_xy_mm_per_min']}")
        if any(abs(m.spindle[1] - st["spindle_speed_rpm"]) > 0.5 for m in run):
            errors.append(f"finishing: wall {c['feature']} cut at {run[0].spindle[1]} rpm, step {n}'s speed is {st['spindle_speed_rpm']}")
    if step_start1 is not None:
        a = min(cut_times[c["id"]][0] for c in walls.values())
        b = max(cut_times[c["id"]][1] for c in walls.values())
        cmp_time("finishing", f"step {n} temp_state_min", ((a + b) / 2 - step_start1) / 60.0, st["temp_state_min"], unit="min")

# --- probing ------------------------------------------------------------------------------------
insp = evs[2]
pr_mo = runs["probing"][1]
logs = [(i, e[1]) for i, e in enumerate(insp) if e[0] == "LOG"]
if len(logs) != len(points):
    errors.append(f"probing: {len(logs)} LOG lines, {len(points)} planned points")
measuring = protected = 0
k = 0
prev_end = None
for n, m in enumerate(pr_mo):
    if m.kind != "STRAIGHT_PROBE":
        prev_end = m.end
        continue
    if k >= len(points):
        errors.append(f"probing: STRAIGHT_PROBE {n + 1} (line {m.line}) after the last planned point")
        break
    p = points[k]
    contact, appr = p["contact_mm"], p["approach"]
    start = [contact[a] - args.approach * appr[a] for a in range(3)]
    end = [contact[a] + args.overtravel * appr[a] for a in range(3)]
    where = f"probing: point {p['feature']} {p['point']} (position {p['position']})"
    if m.measuring:
        measuring += 1
        if not close(m.end[:3], end):
            errors.append(f"{where}: measuring target {list(m.end[:3])}, planned {end}")
        if abs(m.end[5] - p.get("c_deg", 0.0)) > CTOL:
            errors.append(f"{where}: probed at C {m.end[5]}, planned {p.get('c_deg')}")
        if prev_end is None or not close(prev_end[:3], start):
            errors.append(f"{where}: the measuring move starts at {list(prev_end[:3]) if prev_end else None}, planned start {start}")
        fields = insp[m.ev + 1:]
        text = next((e[1] for e in fields if e[0] == "LOG"), "")
        f = text.split()
        if len(f) != 6 or float(f[0]) != 1 or int(f[1]) != p["position"] or int(f[2]) != p["point"]:
            errors.append(f"{where}: LOG 'PT {text}', expected 'PT 1 {p['position']} {p['point']} x y z'")
        if m.spindle[0]:
            errors.append(f"{where}: probing with the spindle turning")
        if "time_in_cycle_s" in p:
            cmp_time("probing", f"point {p['feature']} {p['point']} time_in_cycle_s", m.t1, p["time_in_cycle_s"])
        k += 1
        prev_end = tuple(contact) + m.end[3:]  # the controller stops at the contact
    else:
        protected += 1
        if not close(m.end[:3], start):
            errors.append(f"{where}: protected move to {list(m.end[:3])}, planned start {start}")
        prev_end = m.end
if k != len(points):
    errors.append(f"probing: {k} measuring moves, {len(points)} planned points")

if errors:
    sys.stdout.reconfigure(errors="replace")
    print("rs274 check of the stepped workpiece FAILED:")
    for e in errors[:40]:
        print("  " + e)
    if len(errors) > 40:
        print(f"  ... and {len(errors) - 40} more")
    print("  worst time differences: " + ", ".join(f"{n} {worst[n]:.2e} s" for n in names))
    sys.exit(1)
print(f"rs274 check ok ({sw.get('experiment')}, {sw.get('transition')}): {len(fin_cuts)} finishing cuts in order "
      f"({len(tops)} top lanes, {sum(1 for c in fin_cuts if wall_re.match(c['feature']))} walls at their floor's depth), "
      f"{len(steps)} steps, {len(fin_dw)} warm-up dwells of {fin_dw[0][1] if fin_dw else 0:.0f} s ({air_feeds} feeds in the air); "
      f"probing {measuring} measuring + {protected} protected moves (approach {args.approach} mm, overtravel {args.overtravel} mm), "
      f"{len(logs)} LOG lines; no ABORT")
print("  rs274 timing: " + ", ".join(f"{n} {runs[n][0]:.3f} s" for n in names) +
      f"; machine off {waits[0]:.1f} s and {waits[1]:.1f} s" + ("" if desc is not None else " (no --part: not checked)"))
print("  max |rs274 - manifest| time: " + ", ".join(f"{n} {worst[n]:.2e} s" for n in names) + f" (tolerance {TTOL} s)")
