#!/usr/bin/env python3
"""Writes the hand-written seeds of fuzz/corpus/ (the hostile inputs: truncated files, huge
counts, NaN/inf, deep nesting, DOCTYPE entities ...) and copies the project's own small sample
files beside them. Run from the repository root; idempotent. The seeds taken from probeloop's
own outputs (plans, programs, logs, QIF/DMIS documents) are written by fuzz/make_output_seeds.sh.
The libFuzzer runs of scripts/fuzz.sh never write into fuzz/corpus/ (they work on a copy)."""
import glob, os, shutil, struct, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
C = os.path.join(ROOT, "fuzz", "corpus")
NIST = os.path.join(ROOT, "..", "shared", "refdata", "nist-ls")


def put(harness, name, data):
    d = os.path.join(C, harness)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def copy(harness, path, name=None):
    if os.path.exists(path):
        put(harness, name or os.path.basename(path), open(path, "rb").read())


# --- PLY ---------------------------------------------------------------------------------------
hdr = lambda fmt, n, extra="": (f"ply\nformat {fmt} 1.0\ncomment seed\nelement vertex {n}\n"
                                f"property float x\nproperty float y\nproperty double z\n{extra}end_header\n")
pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1.5)]
put("ply", "ascii.ply", hdr("ascii", 4) + "".join(f"{x} {y} {z}\n" for x, y, z in pts))
put("ply", "ascii_faces.ply",
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
    "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0 255\n1 0 0 0\n0 1 0 7\n3 0 1 2\n")
for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    body = b"".join(struct.pack(e + "ffd", *p) for p in pts)
    put("ply", f"{fmt}.ply", hdr(fmt, 4).encode() + body)
    # a list property of every count type, and a second element after the vertices
    h = (f"ply\nformat {fmt} 1.0\nelement vertex 2\nproperty int x\nproperty short y\nproperty uint z\n"
         "property list ushort char extra\nelement face 1\nproperty list uint float f\nend_header\n")
    b = struct.pack(e + "ihI", 1, -2, 3) + struct.pack(e + "H", 2) + b"\x01\x02"
    b += struct.pack(e + "ihI", 4, 5, 6) + struct.pack(e + "H", 0)
    b += struct.pack(e + "I", 1) + struct.pack(e + "f", 0.5)
    put("ply", f"{fmt}_lists.ply", h.encode() + b)
    put("ply", f"hostile_{fmt}_truncated.ply", hdr(fmt, 4).encode() + body[:13])
    put("ply", f"hostile_{fmt}_nan.ply", hdr(fmt, 1).encode() + struct.pack(e + "ffd", float("nan"), 0, float("inf")))
    put("ply", f"hostile_{fmt}_negative_list.ply",
        (f"ply\nformat {fmt} 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
         "property list char float l\nend_header\n").encode() + struct.pack(e + "fffb", 1, 2, 3, -1) + b"\0" * 16)
put("ply", "regress-element-count-1e20.ply", hdr("ascii", "99999999999999999999") + "0 0 0\n")
put("ply", "hostile_huge_count_binary.ply", hdr("binary_little_endian", "1e300").encode() + b"\0" * 16)
put("ply", "hostile_empty_elements.ply",
    "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
    "property float z\nelement nothing 4000000000\nend_header\n" + "\0" * 12)
put("ply", "hostile_no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n")
put("ply", "hostile_ascii_inf.ply", hdr("ascii", 2) + "0 0 0\ninf nan 1e999\n")
put("ply", "hostile_ascii_list_huge.ply",
    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
    "property list uchar int l\nend_header\n0 0 0 1e300 1\n")
put("ply", "hostile_crlf.ply", (hdr("ascii", 1) + "1 2 3\n").replace("\n", "\r\n"))

# --- XYZ, NIST .ds, fit CSV ---------------------------------------------------------------------
put("xyz", "points.xyz", "# x y z\n0 0 0\n1,0,0\n0 1 0 extra 7\n\n0\t0\t1\n")
put("xyz", "hostile.xyz", "1 2\nnan 0 0\n1e999 0 0\n0x10 0 0\n- 1 2\n")
put("xyz", "hostile_crlf_bom.xyz", "\ufeff1 2 3\r\n4 5 6\r\n")
for f in ("Sphere/sph9.ds", "Plane/pla7.ds", "Cone/con7.ds", "Cylinder/cyl27.ds"):
    copy("nist_ds", os.path.join(NIST, f))
put("nist_ds", "hostile_count_huge.ds", "99999999999\n0 0 0\n")
put("nist_ds", "regress-count-1e300.ds", "1e300\n0 0 0\n")
put("nist_ds", "hostile_count_negative.ds", "-3\n0 0 0\n")
put("nist_ds", "hostile_count_short.ds", "4\n0 0 0\n1 1 1\n")
put("nist_ds", "hostile_nan.ds", "2\n0 0 nan\ninf 0 0\n")
put("nist_ds", "hostile_count_fraction.ds", "2.5\n0 0 0\n1 1 1\n2 2 2\n")
put("fit_csv", "points.csv", "x_mm,y_mm,z_mm,nx,ny,nz,feature\n0,0,0,0,0,1,S1\n1,0,0,1,0,0,S1\n0,1,0,0,1,0,S2\n")
put("fit_csv", "semicolon.csv", "x;y;z\n0,5;1;2\n3;4,25;5\n")
put("fit_csv", "hostile.csv", "x,y,z,nx,ny,nz\n0,0,0,0,0,0\n1,nan,0\n,,,\n1,2,3,4,5,6,7\n")
put("fit_csv", "hostile_both_separators.csv", "x,y;z\n1,2;3\n")
copy("fit_csv", os.path.join(ROOT, "examples", "block_cmm_points.csv"))

# --- points CSV, probe logs (sphere artifact plan: fuzz/fixtures/sphere_plan.json) ---------------
put("points_csv", "regress-cycle-1e11.csv", "cycle,c_deg,x_mm,y_mm,z_mm\n99999999999,0,0,0,0\n2147483648,0,1,1,1\n")
put("points_csv", "hostile_nan.csv", "cycle,c_deg,x_mm,y_mm,z_mm,point\n1,nan,0,0,0,1\n1,0,inf,0,0,-1\n1,1e308,0,0,0,0\n")
put("points_csv", "cycle_starts.csv", "cycle,start_s\n1,0\n2,3600\n3,7200\n")
put("points_csv", "hostile_cycle_starts.csv", "cycle,start_s\n1,0\n1,0\n-5,1e308\n3,nan\n")
put("probe_log", "linuxcnc.log", "PT 1.000000 1 1 -141.000000 0.500000 75.000000\nPT 1.000000 1 2 -140.000000 0.500000 76.000000\n")
put("probe_log", "fanuc.txt", "%\nSTART  20260131  235958\nPT     1 2 5  - 160.0010   18.0000  93.0020  20260131  235959\n"
    "START  20260201       2\nPT     1 2 6  - 160.0010   18.0000  93.0020  20260201       3\n%\n")
put("probe_log", "hostile.log", "PT 2147483648 1 1 0 0 0\nPT -1 -1 -1 0 0 0\nPT 1 1 0 0 0 0\nPT 1 1 1 nan 0 0\nPT 1 1 1 1e309 0 0\n")
put("probe_log", "hostile_clock.txt", "START 99999999 999999\nPT 1 1 1 0 0 0 00000000 000000\nSTART 20260229 250000\n")
put("probe_log", "hostile_truncated.log", "PT 1.000000 1 1 -141.0000")

# --- model inputs / errors CSV -----------------------------------------------------------------
put("inputs_errors_csv", "inputs.csv", "# c\ntime_s,T_env_C,c_rpm\n0,20,0\n60,21,300\n120,22,300\n")
put("inputs_errors_csv", "errors.csv", "time_s,cycle,EY0C_um,U_EY0C_um\n60,1,0,0\n120,2,1.5,2.2\n")
put("inputs_errors_csv", "hostile_gap.csv", "time_s,T\n0,20\n60,20\n120,20\n300,20\n")
put("inputs_errors_csv", "hostile_nan.csv", "time_s,T,U_T\n0,nan,1\n1e308,1e308,-1\n-1e308,inf,0\n")
put("inputs_errors_csv", "hostile_step_tiny.csv", "time_s,T\n0,1\n1e-300,2\n2e-300,3\n1e300,4\n")
put("inputs_errors_csv", "hostile_semicolon.csv", "time_s;EY0C_um;U_EY0C_um\n0;1,5;0,1\n1;2;3\n")

# --- YAML ---------------------------------------------------------------------------------------
for f in glob.glob(os.path.join(ROOT, "parts", "machines", "*.yaml")):
    copy("machine_yaml", f)
for f in ("sphere_artifact.yaml", "thermal_test_piece.yaml", "stepped_workpiece.yaml"):
    copy("test_piece_yaml", os.path.join(ROOT, "parts", f))
copy("test_piece_yaml", os.path.join(ROOT, "examples", "workpiece_block.yaml"))
for f in ("truth_campaign.yaml", "truth_machining.yaml", "truth_rigid.yaml", "truth_thermal_test.yaml"):
    copy("truth_yaml", os.path.join(ROOT, "examples", f))
copy("truth_yaml", os.path.join(ROOT, "examples", "stepped_workpiece", "truth.yaml"), "sw_truth.yaml")
copy("error_model_yaml", os.path.join(ROOT, "examples", "model", "start.yaml"))
copy("error_model_yaml", os.path.join(ROOT, "examples", "stepped_workpiece", "yaqoob2017_components.yaml"))
for f in glob.glob(os.path.join(ROOT, "tests", "data", "hidden", "*.yaml"))[:2]:
    copy("truth_yaml", f, "hidden_" + os.path.basename(f))
for f in glob.glob(os.path.join(ROOT, "examples", "gum", "*.yaml")):
    copy("gum_model_yaml", f)
deep_map = "kind: machine\nname:\n" + "".join("  " * i + f"k{i}:\n" for i in range(1, 120)) + "  " * 120 + "x: 1\n"
deep_flow = "kind: sphere_artifact\nsphere: " + "[" * 5000 + "]" * 5000 + "\n"
deep_brace = "kind: gum_model\ninputs: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n"
laughs = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [" + ", ".join([f"*{chr(97 + i)}"] * 10) + "]\n" for i in range(8))
for h in ("machine_yaml", "test_piece_yaml", "truth_yaml", "error_model_yaml", "gum_model_yaml"):
    put(h, "hostile_deep_block.yaml", deep_map)
    put(h, "hostile_deep_flow.yaml", deep_flow)
    put(h, "hostile_deep_brace.yaml", deep_brace)
    put(h, "hostile_aliases.yaml", laughs)
    put(h, "hostile_values.yaml", "kind: x\na: .nan\nb: .inf\nc: -.inf\nd: 1e999\ne: 99999999999999999999\nf: 0x7fffffff\n"
        "g: !!binary AAAA\nh: ~\na: duplicate\n\t- tab\n")
    put(h, "hostile_truncated.yaml", "kind: machine\nname: 'unterminated\n  - [1, 2\n")
put("gum_model_yaml", "hostile_units.yaml",
    "kind: gum_model\ntitle: t\noutputs:\n  - {name: y, expression: \"x/0 + log(-x) + sqrt(-1) + acos(2) + " + "(" * 200 + "x" + ")" * 200 + "\", unit: mm}\n"
    "inputs:\n  - {name: x, value: 1e308, u: 1e308, unit: mm}\n")

# --- JSON ---------------------------------------------------------------------------------------
put("compensation_json", "compensation.json",
    '{"format": "probeloop-compensation", "kind": "stepped_workpiece", "experiment": "W8", "steps": ['
    '{"step": 1, "wall_um": {"XP": 1.5, "XN": -2, "YP": 0, "YN": 3}, "floor_um": 4, "U_wall_um": {"XP": 1, "XN": 1, "YP": 1, "YN": 1}, "U_floor_um": 2},'
    '{"step": 2, "wall_um": {"XP": 0, "XN": 0, "YP": 0, "YN": 0}, "floor_um": 0}], "basis": "hand"}')
put("compensation_json", "regress-step-1e300.json",
    '{"format": "probeloop-compensation", "kind": "stepped_workpiece", "experiment": "W8", "steps": ['
    '{"step": 1e300, "wall_um": {"XP": 0, "XN": 0, "YP": 0, "YN": 0}, "floor_um": 0}]}')
for h in ("compensation_json", "manifest_json"):
    put(h, "hostile_deep.json", "[" * 20000 + "]" * 20000)
    put(h, "hostile_numbers.json", '{"format": "probeloop-compensation", "steps": [{"step": 1e400, "wall_um": {"XP": NaN}}], '
        '"kind": 18446744073709551616, "experiment": -0.0}')
    put(h, "hostile_truncated.json", '{"format": "probeloop-plan", "features": [{"id": "A", "points": [')

# --- GUM expressions ----------------------------------------------------------------------------
for i, e in enumerate(["l_s + d - l_s*(dalpha*theta + alpha_s*dtheta)", "m_R*(1 + x) - y^2/z", "-x^2 + pi",
                       "sqrt(x) + exp(y) + log(z) + log10(U) + sin(theta) + cos(theta) + tan(d) + asin(d) + acos(d) + atan(d) + abs(y)",
                       "atan2(y, x) + pow(x, 2.5) + hypot(x, y)", "1e-6*x + 2.5E+3", "x^y^z", "((x))"]):
    put("gum_expression", f"model{i}.txt", e)
put("gum_expression", "hostile_deep_parens.txt", "(" * 20000 + "x" + ")" * 20000)
put("gum_expression", "hostile_deep_unary.txt", "-" * 30000 + "x")
put("gum_expression", "hostile_deep_power.txt", "x" + "^x" * 15000)
put("gum_expression", "hostile_deep_calls.txt", "sqrt(" * 10000 + "x" + ")" * 10000)
put("gum_expression", "hostile_numbers.txt", "1e999 + 1e-999 + 0x1p3 + nan + inf + 1.2.3 + x/0 + log(0) + pow(0, -1)")
put("gum_expression", "hostile_unknown.txt", "y + unknown_name(x) + atan2(x) + ")

# --- G-code -------------------------------------------------------------------------------------
copy("gcode_linuxcnc", os.path.join(ROOT, "examples", "block_face_and_wall.ngc"))
put("gcode_linuxcnc", "hostile_loop.ngc", "o100 while [1]\nG1 X1 F100\no100 endwhile\nM2\n")
put("gcode_linuxcnc", "hostile_params.ngc", "#1=1e308\n#2=[#1*#1]\n#<x>=[#2-#2]\nG1 X#2 F#1\n#99999999=1\n#-1=2\n#[0/0]=3\nG0 X[sqrt[-1]]\nM2\n")
put("gcode_linuxcnc", "regress-deep-brackets.ngc", "#1=" + "[" * 5000 + "1" + "]" * 5000 + "\n" +
    "".join(f"o{i} if [1]\n" for i in range(1, 300)) + "".join(f"o{i} endif\n" for i in range(299, 0, -1)) + "M2\n")
put("gcode_linuxcnc", "hostile_probe.ngc", "G90 G54\nT1 M6\nG43 H1\nG38.2 Z-10 F100\nG38.3 Z-1e308 F1e-308\nG4 P1e308\nG10 L2 P9 X1\n"
    "(LOGOPEN,a.txt)\n(LOG,#5061 #5063 #<_x>)\n(LOGCLOSE)\nG2 X10 Y0 I5 J0 F100\nG3 X0 Y0 I-5 J0\nG2 X0 Y0 I0 J0\nM30\n")
put("gcode_fanuc", "hostile_loop.nc", "%\nO0001\nN10 #1=1\nWHILE[#1GT0]DO1\nG1 X1 F100\nEND1\nGOTO10\nM30\n%\n")
put("gcode_fanuc", "hostile_goto.nc", "N1 GOTO1\nM30\n")
put("gcode_fanuc", "hostile_params.nc", "#1=1e308\n#2=#1*#1\nIF[#2EQ#2]GOTO5\nN5 #3000=1(ALARM)\n#500=[1/0]\nG31 Z-1e308 F0\nPOPEN\nDPRNT[X*#5061[53]]\nPCLOS\nM30\n")
put("gcode_fanuc", "hostile_nesting.nc", "".join(f"WHILE[1LT0]DO{i % 3 + 1}\n" for i in range(200)) + "M30\n")

# --- feature actuals (issue 34) ----------------------------------------------------------------
# The thermal test piece's features at their nominal geometry (every one of the fuzz plan, the
# datum band as a circle), under foreign ids: the whole features route; and hostile rows.
import json  # noqa: E402
FA = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points\n"
plan = json.load(open(os.path.join(ROOT, "fuzz", "fixtures", "ttp_plan.json")))
rows = []
for k, f in enumerate(plan["features"]):
    (x, y, z), (i, j, kk) = f["point_mm"], f["direction"]
    if f["kind"] == "cylinder":
        rows.append(f"1,F{k},circle,{x},{y},{z},{i},{j},{kk},{2 * f['radius_mm']},1.1,12")
    else:
        rows.append(f"1,F{k},plane,{x},{y},{z},{i},{j},{kk},,2.4,12")
put("feature_actuals", "ttp_nominal_foreign_ids.csv", FA + "\n".join(rows) + "\n")
put("feature_actuals", "sphere_centres.csv", FA + "1,S1,sphere,-160,0,75,,,,30,0.5,25\n1,S2,sphere,0,160,75,,,,30,,25\n")
put("feature_actuals", "hostile_rows.csv", FA + "1,TOP,plane,nan,0,0,0,0,1,,1,12\n1,CYL,circle,0,0,0,0,0,0,-5,,1e300\n"
    "2,Z1,plane,0,0,-12,0,0,1,,,3\n1,FLANK_P,plane,1e308,1e308,1e308,1e-300,0,0,,inf,9\n1,X,cone,0,0,0,,,,,,1\n")
put("feature_actuals", "hostile_ambiguous.csv", FA + "".join(f"1,P{k},plane,0,{-6.0 + 1e-9 * k},-12.1,0,0,1,,1,12\n" for k in range(50)))

# --- QIF, DMIS ----------------------------------------------------------------------------------
for f in ("QIF_Results_Sample.QIF", "mitutoyo_results_serialized_pass_fail_sample.QIF"):
    copy("qif", os.path.join(ROOT, "..", "shared", "refdata", "qif3", "samples", f))
put("qif", "hostile_doctype.qif",
    '<?xml version="1.0"?>\n<!DOCTYPE QIFDocument [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
    '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]>\n'
    '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0"><Header>&d;</Header></QIFDocument>\n')
put("qif", "hostile_external_entity.qif",
    '<?xml version="1.0"?>\n<!DOCTYPE QIFDocument [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
    '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0">&x;</QIFDocument>\n')
put("qif", "hostile_deep.qif", '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0">' + "<a>" * 3000 + "</a>" * 3000 + "</QIFDocument>")
put("qif", "hostile_truncated.qif", '<?xml version="1.0"?>\n<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0"><Features><Feat')
put("dmis", "hostile_counts.dmo", "DMISMN/'x',05.3\nUNITS/MM,ANGDEC\nF(S1)=FEAT/SPHERE,OUTER,CART,0,0,0,25\nMEAS/SPHERE,F(S1),99999999999\n"
    "PTMEAS/CART,nan,0,0,0,0,1\nENDMES\nENDFIL\n")
put("dmis", "hostile_truncated.dmi", "DMISMN/'x',05.3\nUNITS/MM,ANGDEC\nF(S1)=FEAT/SPHERE,OUTER,CART,0,0")
put("dmis", "hostile_continuation.dmi", "DMISMN/'x',05.3\n" + "F(A)=FEAT/PLANE,CART,$\n" * 2000 + "ENDFIL\n")
# The lenient reader's paths (issue 34): labels defined and reported again, a MEAS block without
# ENDMES, a stray ENDMES, statements after ENDFIL, a missing ENDFIL.
put("dmis", "hostile_lenient.dmi", "DMISMN/'x',05.3\nF(A)=FEAT/PLANE,CART,0,0,0,0,0,1\nF(A)=FEAT/PLANE,CART,0,0,5,0,0,1\n"
    "MEAS/PLANE,F(A),1\nPTMEAS/CART,1,2,5,0,0,1\nMEAS/PLANE,F(A),1\nPTMEAS/CART,3,4,5,0,0,1\nENDMES\nENDMES\nENDFIL\nGOTO/0,0,1\n")
put("dmis", "hostile_lenient.dmo", "FILNAM/'x'\nFA(C)=FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,10\nFA(C_P01)=FEAT/POINT,CART,5,0,0,1,0,0\n"
    "FA(C_P01)=FEAT/POINT,CART,5.1,0,0,1,0,0\nFA(C)=FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,10.2\nFA(C)=FEAT/PLANE,CART,0,0,0,0,0,1\n")
print("seeds written under", C)
