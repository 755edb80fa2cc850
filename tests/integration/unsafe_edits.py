"""Seeded unsafe programs: edits of programs `probeloop plan` emitted, each with the finding the
safety verifier (`probeloop check`) must report. Shared by check_cli.py (the verifier through the
CLI, both dialects) and linuxcnc_safety.py (the LinuxCNC-dialect ones run on LinuxCNC in
simulation).

An edit takes the program's lines and returns (lines, (rule, 1-based line), allowed): the rule the
verifier must report at that line, and the other (rule, line) findings the edit explains. The
insertions of NONFINITE make a coordinate that is not a finite number: the verifier cannot
evaluate such a program and refuses it with exit 2 naming the line and the expression."""
import re


def first(lines, pattern, start=0):
    for i in range(start, len(lines)):
        if re.match(pattern, lines[i]):
            return i
    raise AssertionError(f"no line matches {pattern}")


def off_travel(lines):  # the tool-change height 20 mm above the Z travel (500 mm)
    i = first(lines, r"G53 G0 Z500\.0000")
    lines[i] = "G53 G0 Z520.0000"
    return lines, ("travel", i + 1), set()


def rapid_through_sphere(lines):  # a retract to Z80 instead of the clearance plane: the next XY rapid crosses the sphere
    i = first(lines, r"G0 Z113\.0000", first(lines, r"\(LOG,PT|DPRNT\[PT"))
    lines[i] = "G0 Z80.0000"
    return lines, ("collision", i + 2), {("positioning-unprotected", i + 2)}


def no_contact_check(lines):  # the #5070 check after the first protected move removed
    i = first(lines, r"G38\.3 ")
    del lines[i + 1:i + 4]
    return lines, ("probe-unprotected", i + 1), set()


def unprotected_descent(lines):  # the protected descent beside the sphere as a plain rapid
    i = first(lines, r"G38\.3 ")
    lines[i] = "G0" + lines[i][len("G38.3"):lines[i].index(" F")]
    del lines[i + 1:i + 4]
    return lines, ("positioning-unprotected", i + 1), set()


def c_below_clearance(lines):  # C indexed to 90 deg with the tip ball 7 mm above the sphere's top (tip centre Z100, top Z90, tip radius 3)
    i = first(lines, r"G0 C90\.000")
    assert lines[i - 1] == "G0 Z113.0000", lines[i - 1]
    lines[i - 1] = "G0 Z100.0000"  # itself a descent toward the sphere, and the next rapid closes in on it turned
    return lines, ("rotary-below-clearance", i + 1), {("positioning-unprotected", i), ("positioning-unprotected", i + 2)}


def spindle_with_probe(lines):  # M3 right after the probe comes in
    i = first(lines, r"G43 H99")
    lines.insert(i + 1, "S1000 M3")
    return lines, ("spindle-with-probe", i + 2), set()


def no_trigger_check(lines):  # Fanuc: the measuring G31's skip-position check removed
    i = first(lines, r".*PROBE DID NOT TRIGGER")
    del lines[i]
    return lines, ("probe-unprotected", i), set()


def rapid_through_stock(lines):  # roughing: the rapid to level 2's start goes down to Z60 on its way, through level 1's floor
    i = first(lines, r"G0 Z85\.0000", first(lines, r"G1 ") + 1)
    j = first(lines, r"G0 X", i)
    lines[j] = lines[j] + " Z60.0000"
    return lines, ("collision", j + 1), set()


# The sphere-cycle edits of check_cli.py section 2: (name, dialect of the edited program, edit).
SPHERE_CASES = [
    ("off_travel", "linuxcnc", off_travel),
    ("rapid_through_sphere", "linuxcnc", rapid_through_sphere),
    ("rapid_through_sphere_fanuc", "fanuc", rapid_through_sphere),
    ("no_contact_check", "linuxcnc", no_contact_check),
    ("no_trigger_check_fanuc", "fanuc", no_trigger_check),
    ("unprotected_descent", "linuxcnc", unprotected_descent),
    ("c_below_clearance", "linuxcnc", c_below_clearance),
    ("spindle_with_probe", "fanuc", spindle_with_probe),
]

# Coordinates that are not numbers (issue 28), check_cli.py section 5: (name, dialect, the line
# after which the lines are inserted, the inserted lines, which inserted line (1-based) the
# verifier refuses, the start of its message).
BIG = "1" + "0" * 308  # 1e308: finite; ten times it is not
NONFINITE = [
    ("nan_then_rapid_into_sphere", "linuxcnc", "G43 H99",
     ["#901 = [EXP[1000]]", "#902 = [#901 - #901]", "G0 Z#902", "G0 Z80.0000"], 1, "EXP in"),
    ("overflowing_coordinate", "linuxcnc", "G43 H99", [f"G0 Z[{BIG} * 10]"], 1, "a product in"),
    ("nan_plunge_fanuc", "fanuc", "G43 H99", ["#901=EXP[1000.]", "#902=#901-#901", "G1 Z#902 F100."], 1, "EXP in"),
    ("offset_overflow_fanuc", "fanuc", "G43 H99", [f"#901={BIG}.", "G0 X[#901+#901]"], 2, "a sum in"),
]


def insert_after(lines, after, insert):
    """The lines with `insert` after the first line matching `after`; returns (lines, index of that line)."""
    i = first(lines, after)
    lines[i + 1:i + 1] = insert
    return lines, i


def rapid_only(lines):
    """The rapid of nan_then_rapid_into_sphere without the NaN move before it (check_cli.py: a
    finding, exit 3; the NaN used to hide it)."""
    lines, i = insert_after(lines, "G43 H99", ["G0 Z80.0000"])
    return lines, i
