#include "evaluate/ingest.hpp"

#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "gcode/probe_log.hpp"

namespace probeloop::evaluate {

PointsFormat parsePointsFormat(const std::string& n) {
  if (n == "auto") return PointsFormat::Auto;
  if (n == "linuxcnc") return PointsFormat::LinuxCncLog;
  if (n == "fanuc") return PointsFormat::FanucDprnt;
  if (n == "csv") return PointsFormat::PointsCsv;
  throw InputError("", 0, "--format '" + n + "': expected auto, linuxcnc, fanuc or csv");
}

namespace {

bool looksLikeCsv(const std::string& text) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    return line.find(',') != std::string::npos;
  }
  return false;
}

std::vector<ProbeRecord> fromCsv(const std::string& text, const std::string& file,
                                 const parts::PlanManifest& m) {
  const CsvTable t = parseCsv(text, file);
  auto need = [&](const char* name) {
    const int c = t.column(name);
    if (c < 0)
      throw InputError(file, t.header_line,
                       std::string("missing column '") + name +
                           "'; a sphere-artifact campaign needs cycle,c_deg,x_mm,y_mm,z_mm");
    return c;
  };
  const int c_cycle = need("cycle"), c_c = need("c_deg"), c_x = need("x_mm"), c_y = need("y_mm"),
            c_z = need("z_mm");
  const int c_time = t.column("time_s"), c_feat = t.column("feature"), c_pt = t.column("point");
  std::vector<ProbeRecord> out;
  std::map<std::pair<int, int>, int> seen;  // (cycle, position) -> points so far
  for (const auto& row : t.rows) {
    ProbeRecord r;
    r.file = file;
    r.line = row.line;
    const double cyc = t.number(row, c_cycle);
    if (cyc != std::round(cyc) || cyc < 1)
      throw InputError(file, row.line, "cycle must be a positive integer");
    r.cycle = static_cast<int>(cyc);
    const double c = t.number(row, c_c);
    if (c_feat >= 0) {
      const std::string& f = row.fields[c_feat];
      for (const auto& s : m.spheres)
        if (s.id == f) r.position = s.position;
      if (r.position == 0)
        throw InputError(file, row.line, "feature '" + f + "' is not in the manifest");
      if (std::fabs(m.sphere(r.position)->c_deg - c) > 1e-6)
        throw InputError(file, row.line, "c_deg " + formatNumber(c) + " does not match feature " + f);
    } else {
      for (const auto& s : m.spheres)
        if (std::fabs(s.c_deg - c) < 1e-6) r.position = s.position;
      if (r.position == 0)
        throw InputError(file, row.line, "c_deg " + formatNumber(c) + " is not a planned C position");
    }
    const int nth = ++seen[{r.cycle, r.position}];
    if (c_pt >= 0) {
      const double p = t.number(row, c_pt);
      if (p != std::round(p) || p < 1)
        throw InputError(file, row.line, "point must be a positive integer");
      r.point = static_cast<int>(p);
    } else {
      r.point = nth;  // points in the planned order
    }
    r.tip_mm = {t.number(row, c_x), t.number(row, c_y), t.number(row, c_z)};
    if (c_time >= 0) r.time_s = t.number(row, c_time);
    out.push_back(r);
  }
  return out;
}

}  // namespace

std::vector<ProbeRecord> readProbeRecords(const std::string& path, PointsFormat format,
                                          const parts::PlanManifest& m) {
  const std::string text = readFile(path);
  if (format == PointsFormat::Auto)
    format = looksLikeCsv(text) ? PointsFormat::PointsCsv : PointsFormat::LinuxCncLog;
  std::vector<ProbeRecord> out;
  if (format == PointsFormat::PointsCsv) {
    out = fromCsv(text, path, m);
  } else {
    for (const auto& p : gcode::parseProbeLog(text, path)) {
      ProbeRecord r;
      r.file = path;
      r.line = p.line;
      r.cycle = p.cycle;
      r.position = p.position;
      r.point = p.point;
      r.tip_mm = p.tip_mm;
      out.push_back(r);
    }
  }
  // Every record must belong to the plan.
  const int per = m.pointsPerSphere();
  std::set<std::tuple<int, int, int>> keys;
  for (const auto& r : out) {
    if (r.cycle > m.cycles)
      throw InputError(path, r.line, "cycle " + std::to_string(r.cycle) + " is beyond the plan's " +
                                         std::to_string(m.cycles) + " cycles");
    const auto* s = m.sphere(r.position);
    if (!s)
      throw InputError(path, r.line, "position " + std::to_string(r.position) +
                                         " is not in the manifest (" +
                                         std::to_string(m.spheres.size()) + " positions)");
    if (r.point > per)
      throw InputError(path, r.line, "point " + std::to_string(r.point) + " of position " +
                                         std::to_string(r.position) + " is not planned (" +
                                         std::to_string(per) + " points per position)");
    if (!keys.insert({r.cycle, r.position, r.point}).second)
      throw InputError(path, r.line, "cycle " + std::to_string(r.cycle) + " position " +
                                         std::to_string(r.position) + " point " +
                                         std::to_string(r.point) + " appears twice");
    const auto& planned = m.points[(r.position - 1) * per + (r.point - 1)];
    // A triggered point lies on its probing line, within the approach/overtravel span of
    // the nominal contact; far away means the log belongs to another plan.
    const double off = (r.tip_mm - planned.contact_mm).norm();
    if (off > 10.0)
      throw InputError(path, r.line, "point is " + formatNumber(off, 3) +
                                         " mm from its planned contact: the log does not match "
                                         "the manifest " + m.file);
  }
  return out;
}

}  // namespace probeloop::evaluate
