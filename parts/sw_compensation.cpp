#include "parts/sw_compensation.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::parts {

namespace {

constexpr double kMaxOffsetUm = 500;

double number(const nlohmann::json& j, const std::string& key, const std::string& where, const std::string& file,
              bool required = true) {
  if (!j.contains(key)) {
    if (!required) return 0;
    throw InputError(file, 0, where + key + ": missing");
  }
  if (!j.at(key).is_number()) throw InputError(file, 0, where + key + ": expected a number");
  const double v = j.at(key).get<double>();
  if (!std::isfinite(v)) throw InputError(file, 0, where + key + ": not a finite number");
  return v;
}

}  // namespace

SwCompensation loadSwCompensation(const std::string& path) {
  SwCompensation c;
  c.file = path;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(readFile(path, kJsonInput));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, 0, std::string("not JSON: ") + e.what());
  }
  if (j.value("format", "") != "probeloop-compensation")
    throw InputError(path, 0, "format: expected \"probeloop-compensation\" (written by probeloop evaluate as compensation.json)");
  if (j.value("kind", "") != "stepped_workpiece") throw InputError(path, 0, "kind: expected \"stepped_workpiece\"");
  if (!j.contains("experiment") || !j.at("experiment").is_string()) throw InputError(path, 0, "experiment: missing");
  c.experiment = j.at("experiment").get<std::string>();
  c.basis = j.value("basis", "");
  if (!j.contains("steps") || !j.at("steps").is_array() || j.at("steps").empty())
    throw InputError(path, 0, "steps: expected a list of the steps' offsets");
  for (std::size_t i = 0; i < j.at("steps").size(); ++i) {
    const auto& s = j.at("steps")[i];
    const std::string where = "steps[" + std::to_string(i) + "].";
    SwStepCompensation x;
    // Compared as a number: converting 1e300 to int first was undefined behaviour, and 1.5 passed as 1.
    const double step = number(s, "step", where, path);
    if (step != static_cast<double>(i + 1))
      throw InputError(path, 0, where + "step: expected " + std::to_string(i + 1) + " (in order from the top), found " +
                                    formatNumber(step));
    x.step = static_cast<int>(i) + 1;
    if (!s.contains("wall_um") || !s.at("wall_um").is_object()) throw InputError(path, 0, where + "wall_um: missing");
    for (int w = 0; w < 4; ++w) {
      x.wall_um[w] = number(s.at("wall_um"), kSwWalls[w], where + "wall_um.", path);
      if (s.contains("U_wall_um")) x.U_wall_um[w] = number(s.at("U_wall_um"), kSwWalls[w], where + "U_wall_um.", path, false);
    }
    x.floor_um = number(s, "floor_um", where, path);
    x.U_floor_um = number(s, "U_floor_um", where, path, false);
    c.steps.push_back(x);
  }
  validateSwCompensation(c);
  return c;
}

void validateSwCompensation(const SwCompensation& c) {
  for (std::size_t i = 0; i < c.steps.size(); ++i) {
    const auto& x = c.steps[i];
    const std::string where = "steps[" + std::to_string(i) + "]";
    if (x.step != static_cast<int>(i) + 1)
      throw InputError(c.file, 0, where + ".step: expected " + std::to_string(i + 1) + " (in order from the top)");
    for (double v : {x.wall_um[0], x.wall_um[1], x.wall_um[2], x.wall_um[3], x.floor_um, x.U_wall_um[0], x.U_wall_um[1],
                     x.U_wall_um[2], x.U_wall_um[3], x.U_floor_um})
      if (!std::isfinite(v)) throw InputError(c.file, 0, where + ": an offset or its U is not finite");
    for (double v : {x.wall_um[0], x.wall_um[1], x.wall_um[2], x.wall_um[3], x.floor_um})
      if (std::fabs(v) > kMaxOffsetUm)
        throw InputError(c.file, 0, where + ": offset " + formatNumber(v) + " um beyond +-" + formatNumber(kMaxOffsetUm) +
                                        " um: a compensation corrects micrometres, not the design");
  }
}

std::string swCompensationJson(const SwCompensation& c) {
  nlohmann::ordered_json j{{"format", "probeloop-compensation"}, {"kind", "stepped_workpiece"}, {"experiment", c.experiment}};
  if (!c.basis.empty()) j["basis"] = c.basis;
  j["steps"] = nlohmann::ordered_json::array();
  for (const auto& s : c.steps) {
    nlohmann::ordered_json w, uw;
    for (int i = 0; i < 4; ++i) {
      w[kSwWalls[i]] = s.wall_um[i];
      uw[kSwWalls[i]] = s.U_wall_um[i];
    }
    j["steps"].push_back({{"step", s.step}, {"wall_um", w}, {"floor_um", s.floor_um}, {"U_wall_um", uw}, {"U_floor_um", s.U_floor_um}});
  }
  return j.dump(1) + "\n";
}

}  // namespace probeloop::parts
