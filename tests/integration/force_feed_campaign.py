#!/usr/bin/env python3
"""The force/feed hidden-effect campaign on a machined part (tests/data/hidden/force_feed.yaml).

Usage: force_feed_campaign.py OUTDIR    ($PROBELOOP, $PROBELOOP_SOURCE_DIR as the other tests)

Writes a program that side-mills the +Y wall of the bar (force_feed_bar.yaml) to Y 15 in 12
segments of 20 mm, each at its own feed, and a CMM plan of 8 points per segment; runs it on
the virtual VMC with --trace and --cmm-points; fits a plane to each segment with
`probeloop fit plane`; and writes the model's two files:
  OUTDIR/run/inputs.csv  (the simulator's, every 0.1 s: feed_mm_per_min among the inputs)
  OUTDIR/eval/errors.csv (time_s = the middle of each segment's cut, from trace.csv;
                          WALL_Y_um = fitted wall Y - 15 mm; U_WALL_Y_um = 2 u of the fit)
and OUTDIR/truth_deflection.csv (time_s, deflection_y_um of each segment's cut, cuts.json).
Deterministic."""
import csv, json, os, subprocess, sys

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
FEEDS = [600, 200, 900, 400, 1000, 300, 700, 500, 800, 250, 950, 450]  # mm/min, shuffled once
X0, SEG, WALL_Y, R = -120.0, 20.0, 15.0, 5.0


def main(out):
    os.makedirs(f"{out}/eval", exist_ok=True)
    lines = ["(force/feed campaign: side-mill the +Y wall of the bar to Y 15 in 12 segments at their own feeds)",
             "G21 G90 G17 G94", "G10 L2 P6 X0 Y0 Z0 C0", "G59", "T1 M6", "G43 H1", "S8000 M3",
             f"G0 X-160 Y{WALL_Y + R:g} Z60", "G0 Z30", f"G1 X{X0:g} F600"]
    first_segment_line = len(lines) + 1
    for i, f in enumerate(FEEDS):
        lines.append(f"G1 X{X0 + SEG * (i + 1):g} F{f}")
    lines += ["G1 X160 F600", "G0 Z60", "M5", "M2"]
    prog = f"{out}/force_feed.ngc"
    open(prog, "w").write("\n".join(lines) + "\n")
    with open(f"{out}/cmm_points.csv", "w") as fh:
        fh.write("feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n")
        for i in range(len(FEEDS)):
            xc = X0 + SEG * (i + 0.5)
            k = 0
            for dx in (-6, -2, 2, 6):
                for z in (32, 37):
                    k += 1
                    fh.write(f"W{i + 1:02d},{k},{xc + dx:g},{WALL_Y:g},{z},0,1,0\n")
    p = subprocess.run([PL, "simulate", prog, "--machine", f"{SRC}/parts/machines/vmc3.yaml",
                        "--part", f"{SRC}/tests/data/hidden/force_feed_bar.yaml",
                        "--truth", f"{SRC}/tests/data/hidden/force_feed.yaml",
                        "--cmm-points", f"{out}/cmm_points.csv", "--trace", "--out", f"{out}/run", "--seed", "1"],
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("simulate failed: " + p.stderr)
    trace = list(csv.DictReader(open(f"{out}/run/trace.csv")))
    cuts = json.load(open(f"{out}/run/cuts.json"))
    rows, truth = [], []
    for i, f in enumerate(FEEDS):
        line = first_segment_line + i
        moves = [r for r in trace if int(r["line"]) == line]
        if len(moves) != 1:
            sys.exit(f"trace.csv: expected one move from line {line}, found {len(moves)}")
        t = float(moves[0]["time_s"]) + float(moves[0]["duration_s"]) / 2
        fit = subprocess.run([PL, "fit", "plane", f"{out}/run/cmm_export.csv", "--feature", f"W{i + 1:02d}", "--json"],
                             capture_output=True, text=True)
        if fit.returncode != 0:
            sys.exit("fit failed: " + fit.stderr)
        par = {q["name"]: q for q in json.loads(fit.stdout)["parameters"]}
        rows.append((t, (par["y_mm"]["value"] - WALL_Y) * 1000, 2 * par["y_mm"]["u"] * 1000))
        cut = [c for c in cuts if abs(c["p1_mm"][0] - (X0 + SEG * (i + 1))) < 0.01 and c["removed_mm3"] > 0]
        truth.append((t, cut[0]["deflection_um"][1] if cut else float("nan")))
    with open(f"{out}/eval/errors.csv", "w") as fh:
        fh.write("# force/feed campaign: wall Y deviation of each segment (CMM plane fit), U for k = 2\n")
        fh.write("time_s,cycle,WALL_Y_um,U_WALL_Y_um\n")
        for k, (t, e, U) in enumerate(rows):
            fh.write(f"{t:.3f},{k + 1},{e:.4f},{U:.4f}\n")
    with open(f"{out}/truth_deflection.csv", "w") as fh:
        fh.write("time_s,deflection_y_um\n")
        for t, d in truth:
            fh.write(f"{t:.3f},{d:.6f}\n")


if __name__ == "__main__":
    main(sys.argv[1])
