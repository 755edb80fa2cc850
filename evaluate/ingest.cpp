#include "evaluate/ingest.hpp"

#include <algorithm>
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
    return line.find(',') != std::string::npos || line.find(';') != std::string::npos;
  }
  return false;
}

// The nearest planned contact of a position (1-based point number).
int nearestPlannedPoint(const parts::PlanManifest& m, int position, const Eigen::Vector3d& tip) {
  const int per = m.pointsPerSphere();
  int best = 1;
  double d_best = 1e300;
  for (int k = 1; k <= per; ++k) {
    const double d = (m.points[static_cast<std::size_t>((position - 1) * per + (k - 1))].contact_mm - tip).norm();
    if (d < d_best) d_best = d, best = k;
  }
  return best;
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
  const int per = m.pointsPerSphere();
  const double contact_radius = m.sphere_radius_mm + m.tip_radius_mm;
  std::vector<ProbeRecord> out;
  std::map<std::pair<int, int>, int> unlabelled;                      // (cycle, position) -> points so far
  std::map<std::pair<int, double>, std::vector<std::string>> labels;  // (cycle, C) -> foreign labels met
  for (const auto& row : t.rows) {
    ProbeRecord r;
    r.file = file;
    r.line = row.line;
    const double cyc = t.number(row, c_cycle);
    if (cyc != std::round(cyc) || cyc < 1)
      throw InputError(file, row.line, "cycle must be a positive integer");
    r.cycle = static_cast<int>(cyc);
    const double c = t.number(row, c_c);
    r.tip_mm = {t.number(row, c_x), t.number(row, c_y), t.number(row, c_z)};
    const std::string label = c_feat >= 0 ? row.fields[static_cast<std::size_t>(c_feat)] : std::string();
    bool trusted = false;  // a manifest id: its position, and its point numbers if given
    for (const auto& s : m.spheres)
      if (!label.empty() && s.id == label) {
        r.position = s.position;
        trusted = true;
      }
    if (trusted) {
      if (std::fabs(m.sphere(r.position)->c_deg - c) > 1e-6)
        throw InputError(file, row.line, "c_deg " + formatNumber(c) + " does not match feature " + label);
    } else {
      std::vector<int> at_c;  // the positions planned at this C angle, in order
      for (const auto& s : m.spheres)
        if (std::fabs(s.c_deg - c) < 1e-6) at_c.push_back(s.position);
      if (at_c.empty())
        throw InputError(file, row.line, "c_deg " + formatNumber(c) + " is not a planned C position");
      std::size_t k = 0;
      if (at_c.size() > 1) {
        if (!label.empty()) {
          auto& seen = labels[{r.cycle, c}];
          const auto it = std::find(seen.begin(), seen.end(), label);
          k = static_cast<std::size_t>(it - seen.begin());
          if (it == seen.end()) seen.push_back(label);
        } else {
          // Without labels, by order: the planned number of points to each in turn.
          int counted = 0;
          for (std::size_t j = 0; j < at_c.size(); ++j) counted += unlabelled[{r.cycle, at_c[j]}];
          k = static_cast<std::size_t>(counted / per);
        }
        if (k >= at_c.size())
          throw InputError(file, row.line, "label '" + label + "' would be position " + std::to_string(k + 1) + " at c_deg " +
                                               formatNumber(c) + ", where " + std::to_string(at_c.size()) + " are planned");
      }
      r.position = at_c[k];
      ++unlabelled[{r.cycle, r.position}];
      const auto* s = m.sphere(r.position);
      const double off = std::fabs((r.tip_mm - s->nominal_centre_mm).norm() - contact_radius);
      if (off > 5.0)
        throw InputError(file, row.line, "point is " + formatNumber(off, 3) + " mm off the nominal sphere of position " +
                                             std::to_string(r.position) + " (c_deg " + formatNumber(c) +
                                             "): it fits no planned position");
    }
    if (trusted && c_pt >= 0) {
      const double p = t.number(row, c_pt);
      if (p != std::round(p) || p < 1)
        throw InputError(file, row.line, "point must be a positive integer");
      r.point = static_cast<int>(p);
    } else {
      r.point = nearestPlannedPoint(m, r.position, r.tip_mm);
      r.nearest_point = true;
    }
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
    if (r.nearest_point) continue;  // checked against its nominal sphere when it was read
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
