#include "evaluate/ingest.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <limits>
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
    if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 byte-order mark
    if (line.empty() || line[0] == '#' || line == "\r") continue;
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
  const double contact_radius = m.sphere_radius_mm + m.tip_radius_mm;
  // First every row, so that a label's place among those at one C angle can be told by time.
  std::vector<ProbeRecord> out;
  std::vector<double> c_of;
  std::vector<std::string> label_of;
  std::set<std::pair<int, int>> claimed;  // (cycle, position) named by a manifest id
  for (const auto& row : t.rows) {
    ProbeRecord r;
    r.file = file;
    r.line = row.line;
    const double cyc = t.number(row, c_cycle);
    if (cyc != std::round(cyc) || cyc < 1)
      throw InputError(file, row.line, "cycle must be a positive integer");
    // Checked here, before the conversion to int (1e11 was undefined behaviour: fuzz/points_csv).
    if (cyc > m.cycles)
      throw InputError(file, row.line, "cycle " + formatNumber(cyc) + " is beyond the plan's " + std::to_string(m.cycles) +
                                           " cycles");
    r.cycle = static_cast<int>(cyc);
    const double c = t.number(row, c_c);
    r.tip_mm = {t.number(row, c_x), t.number(row, c_y), t.number(row, c_z)};
    if (c_time >= 0) r.time_s = t.number(row, c_time);
    const std::string label = c_feat >= 0 ? row.fields[static_cast<std::size_t>(c_feat)] : std::string();
    for (const auto& s : m.spheres)
      if (!label.empty() && s.id == label) r.position = s.position;
    if (r.position != 0) {
      if (std::fabs(m.sphere(r.position)->c_deg - c) > 1e-6)
        throw InputError(file, row.line, "c_deg " + formatNumber(c) + " does not match feature " + label);
      claimed.insert({r.cycle, r.position});
      if (c_pt >= 0) {
        const double p = t.number(row, c_pt);
        if (p != std::round(p) || p < 1)
          throw InputError(file, row.line, "point must be a positive integer");
        if (p > m.pointsPerSphere())
          throw InputError(file, row.line, "point " + formatNumber(p) + " of position " + std::to_string(r.position) +
                                               " is not planned (" + std::to_string(m.pointsPerSphere()) +
                                               " points per position)");
        r.point = static_cast<int>(p);
      }
    }
    out.push_back(r);
    c_of.push_back(c);
    label_of.push_back(label);
  }
  // Then the others: the position planned at their C angle, not named by an id in that cycle.
  std::map<std::pair<int, double>, std::vector<std::pair<double, std::string>>> labels_at;  // (cycle, C) -> (first time, label)
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i].position == 0 && !label_of[i].empty() && out[i].time_s) {
      auto& v = labels_at[{out[i].cycle, c_of[i]}];
      auto it = std::find_if(v.begin(), v.end(), [&](const auto& e) { return e.second == label_of[i]; });
      if (it == v.end()) v.emplace_back(*out[i].time_s, label_of[i]);
      else it->first = std::min(it->first, *out[i].time_s);
    }
  for (auto& [key, v] : labels_at) std::sort(v.begin(), v.end());
  for (std::size_t i = 0; i < out.size(); ++i) {
    ProbeRecord& r = out[i];
    if (r.position == 0) {
      const double c = c_of[i];
      std::vector<int> at_c, planned_at_c;  // the positions planned at this C angle, in order
      for (const auto& s : m.spheres)
        if (std::fabs(s.c_deg - c) < 1e-6) {
          planned_at_c.push_back(s.position);
          if (!claimed.count({r.cycle, s.position})) at_c.push_back(s.position);
        }
      if (planned_at_c.empty())
        throw InputError(file, r.line, "c_deg " + formatNumber(c) + " is not a planned C position");
      if (at_c.empty())
        throw InputError(file, r.line, "label '" + label_of[i] + "' at c_deg " + formatNumber(c) +
                                           ": the positions planned there are named by the manifest's ids in this cycle");
      std::size_t k = 0;
      if (at_c.size() > 1) {
        // Repeats at one C angle are the same sphere in the same place: only a label per
        // position and the time tell them apart (the earlier label is the earlier position).
        std::string ids;
        for (int p : at_c) ids += (ids.empty() ? "" : ", ") + std::to_string(p);
        if (label_of[i].empty() || !r.time_s)
          throw InputError(file, r.line, "c_deg " + formatNumber(c) + " holds positions " + ids +
                                             ": a point there needs the manifest's feature id, or a label per position and time_s");
        const auto& v = labels_at.at({r.cycle, c});
        k = static_cast<std::size_t>(std::find_if(v.begin(), v.end(), [&](const auto& e) { return e.second == label_of[i]; }) - v.begin());
        if (k >= at_c.size())
          throw InputError(file, r.line, "label '" + label_of[i] + "' is the " + std::to_string(k + 1) + "th at c_deg " +
                                             formatNumber(c) + " in cycle " + std::to_string(r.cycle) + ", where " +
                                             std::to_string(at_c.size()) + " positions are planned");
      }
      r.position = at_c[k];
    }
    if (r.point == 0) {
      // Not a planned point number: on the position's nominal sphere, paired with the nearest
      // planned contact (for its planned time).
      const auto* s = m.sphere(r.position);
      const double off = std::fabs((r.tip_mm - s->nominal_centre_mm).norm() - contact_radius);
      if (off > 5.0)
        throw InputError(file, r.line, "point is " + formatNumber(off, 3) + " mm off the nominal sphere of position " +
                                           std::to_string(r.position) + " (c_deg " + formatNumber(c_of[i]) +
                                           "): it fits no planned position");
      r.point = nearestPlannedPoint(m, r.position, r.tip_mm);
      r.nearest_point = true;
    }
  }
  return out;
}

}  // namespace

std::vector<ProbeRecord> readProbeRecords(const std::string& path, PointsFormat format,
                                          const parts::PlanManifest& m) {
  const std::string text = readFile(path);
  if (format == PointsFormat::Auto) {
    format = looksLikeCsv(text) ? PointsFormat::PointsCsv : PointsFormat::LinuxCncLog;
    // A file of another kind is named as what it is, not misread line by line.
    const std::string kind = describeContent(text);
    if (format == PointsFormat::LinuxCncLog && !kind.empty() && kind.find("probe log") == std::string::npos)
      throw InputError(path, 0, "this is " + kind + "; a sphere-artifact campaign is evaluated from the probe log the "
                                "cycle writes (LinuxCNC LOG or Fanuc DPRNT: PT lines) or a points CSV");
  }
  if (format == PointsFormat::PointsCsv) {
    const std::string kind = describeContent(text);
    if (kind.rfind("an errors.csv", 0) == 0 || kind.rfind("an inputs.csv", 0) == 0)
      throw InputError(path, 0, "this is " + kind + "; a sphere-artifact campaign is evaluated from the probe log the "
                                "cycle writes (LinuxCNC LOG or Fanuc DPRNT: PT lines) or a points CSV (x_mm,y_mm,z_mm)");
  }
  std::vector<ProbeRecord> out = format == PointsFormat::PointsCsv ? fromCsv(text, path, m) : probeLogRecords(text, path);
  if (out.empty())
    throw InputError(path, 0, "no probe points in the file: nothing to evaluate (expected the cycle's PT lines or points CSV rows)");
  checkRecordsBelongToPlan(out, m, path);
  return out;
}

std::vector<ProbeRecord> probeLogRecords(const std::string& text, const std::string& path, int first_line,
                                         std::optional<double>* session_start_s) {
  std::vector<ProbeRecord> out;
  for (const auto& p : gcode::parseProbeLog(text, path, first_line, session_start_s)) {
    ProbeRecord r;
    r.file = path;
    r.line = p.line;
    r.cycle = p.cycle;
    r.position = p.position;
    r.point = p.point;
    r.tip_mm = p.tip_mm;
    r.time_s = p.time_s;  // Fanuc's clock in the log, when it is there
    out.push_back(r);
  }
  return out;
}

void checkRecordsBelongToPlan(const std::vector<ProbeRecord>& out, const parts::PlanManifest& m,
                              const std::string& path) {
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
}

void applyCycleStarts(parts::PlanManifest& m, const std::string& path) {
  const CsvTable t = parseCsv(readFile(path), path);
  const int cc = t.column("cycle"), cs = t.column("start_s");
  if (cc < 0 || cs < 0)
    throw InputError(path, t.header_line, "expected the columns cycle,start_s (the start of each cycle on the inputs' clock, s)");
  if (t.rows.empty()) throw InputError(path, t.header_line, "no cycles listed");
  if (static_cast<int>(t.rows.size()) > m.cycles)
    throw InputError(path, t.rows[m.cycles].line, "cycle " + std::to_string(m.cycles + 1) + ": the plan " + m.file + " has " +
                                                      std::to_string(m.cycles) + " cycles");
  std::vector<double> starts;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const double c = t.number(r, cc);
    if (c != static_cast<double>(i + 1))
      throw InputError(path, r.line, "cycle: " + r.fields[cc] + "; expected " + std::to_string(i + 1) +
                                         " (every cycle from 1, in order, once)");
    const double s = t.number(r, cs);
    if (!starts.empty() && !(s > starts.back()))
      throw InputError(path, r.line, "start_s: " + r.fields[cs] + " is not after cycle " + std::to_string(i) + "'s " +
                                         formatNumber(starts.back()) + " s");
    starts.push_back(s);
  }
  m.cycle_start_s.assign(m.cycles, std::numeric_limits<double>::quiet_NaN());
  std::copy(starts.begin(), starts.end(), m.cycle_start_s.begin());
}

}  // namespace probeloop::evaluate
