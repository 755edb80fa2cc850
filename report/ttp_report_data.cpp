// The thermal-test-piece report's data: the quantities and their references, the routes, the
// R-test and the machine's logged inputs read from their files (report/ttp_report_parts.hpp).
#include <algorithm>
#include <cmath>
#include <regex>

#include "core/error.hpp"
#include "report/ttp_report_parts.hpp"

namespace probeloop::report::ttp_detail {

using namespace web;

const char* const kThesis = "Blaser 2020 (ETH Diss. 26709)";

// E_X ... dT: the evaluation's ids, the page's labels, the R-test's counterpart, and the
// thesis's section and equation (the project's notes call the thesis seed 004: Sec. 7.2 is its
// measurement and evaluation, Sec. 7.3 the validation).
const Quantity kQuantities[6] = {
    {"EX_um", "E_X", "\u00b5m", "E_X: thermal error in X (Eq. 7.1)", "EX0C_um", "E_X0C", RTestScale::same,
     "R-test E_X0C (apparent)", "Sec. 7.2, Eq. 7.1 (the sign of its last term corrected: see the note on Eqs. 7.1 and 7.2)"},
    {"EY_um", "E_Y", "\u00b5m", "E_Y: thermal error in Y (Eq. 7.2)", "EY0C_um", "E_Y0C", RTestScale::same,
     "R-test E_Y0C (apparent)", "Sec. 7.2, Eq. 7.2 (corrected as Eq. 7.1)"},
    {"EZ_um", "E_Z", "\u00b5m", "E_Z: thermal error in Z (Eq. 7.4)", "EZ0T_um", "E_Z0T", RTestScale::same,
     "R-test E_Z0T (apparent)", "Sec. 7.2, Eq. 7.4"},
    {"EB_urad", "E_B", "\u00b5rad", "E_B: tilt about Y (Eq. 7.5)", "EB0C_urad", "E_B0C", RTestScale::negated,
     "R-test \u2212E_B0C", "Sec. 7.2, Eq. 7.5"},
    {"ETTP_um", "E_TTP", "\u00b5m", "E_TTP: distortion of the test piece (Eq. 7.3)", nullptr, "", RTestScale::none, "",
     "Sec. 7.2, Eq. 7.3 (diametral); beside it Eq. 7.9 (the dial-gauge form, one-sided: half of Eq. 7.3)"},
    {"dT_K", "\u0394T", "K", "\u0394T: temperature equivalent (Eq. 7.10)", "ER0T_um", "E_R0T", RTestScale::table_temperature,
     "R-test: table \u0394T", "Sec. 7.3, Eq. 7.10 (\u03b1 and R of the piece from its description)"},
};

const Quantity* findQuantity(const std::string& id) {
  for (const auto& q : kQuantities)
    if (id == q.id) return &q;
  return nullptr;
}

// Label and unit of any quantity id, known or not ("XYZ_um" -> "XYZ", "µm").
std::pair<std::string, std::string> labelAndUnit(const std::string& id, const std::string& unit_field) {
  if (const Quantity* q = findQuantity(id)) return {q->label, q->unit};
  std::string label = id, unit = unit_field;
  const std::size_t us = id.rfind('_');
  if (us != std::string::npos && us > 0) {
    if (unit.empty()) unit = id.substr(us + 1);
    if (id.substr(us + 1) == unit) label = id.substr(0, us);
  }
  return {label, displayUnit(unit)};
}

// "EX0C_um" -> "E_X0C", "µm".
std::pair<std::string, std::string> rTestLabelAndUnit(const std::string& column) {
  for (const auto& q : kQuantities)
    if (q.r_test != nullptr && column == q.r_test)
      return {q.r_test_name, displayUnit(column.substr(column.rfind('_') + 1))};
  return labelAndUnit(column, "");
}

std::string columnTitle(const std::string& label, const std::string& unit, const std::string& middle) {
  return label + middle + (unit.empty() ? "" : " (" + unit + ")");
}

// ---------------------------------------------------------------------------------------
// Routes (one or two evaluations) and the R-test.

std::string routeName(const std::string& route) {
  if (route == "cmm") return "CMM";
  if (route == "on_machine") return "on-machine (OM)";
  if (route == "gauge") return "gauge";
  return route.empty() ? "test piece" : route;
}

void checkEvaluation(const json& j, const std::string& file) {
  const std::string what = "thermal-test-piece report: the evaluation";
  if (!j.is_object())
    throw InputError(file, 0, what + " is not a JSON object (expected the evaluation.json of `probeloop evaluate`)");
  const std::string kind = text(j, "kind");
  if (kind != "thermal_test_piece")
    throw InputError(file, 0,
                     what + (kind.empty() ? " has no \"kind\"" : " has kind \"" + kind + "\"") +
                         ", expected \"thermal_test_piece\" (the evaluation.json of `probeloop evaluate` with a "
                         "thermal-test-piece manifest)");
  const json* cycles = field(j, "cycles");
  if (cycles == nullptr || !cycles->is_array())
    throw InputError(file, 0, what + " has no \"cycles\" array");
}

const json* findValue(const json& cycle, const std::string& quantity) {
  for (const auto& v : array(cycle, "values"))
    if (text(v, "quantity") == quantity) return &v;
  return nullptr;
}

// The reference cut: phase "reference", else the lowest cycle number, else the first cycle.
std::optional<double> referenceTime(const json& eval) {
  const json* best = nullptr;
  for (const auto& c : array(eval, "cycles")) {
    if (!number(c, "time_s")) continue;
    if (text(c, "phase") == "reference") return number(c, "time_s");
    if (best == nullptr || number(c, "cycle").value_or(1e300) < number(*best, "cycle").value_or(1e300)) best = &c;
  }
  return best ? number(*best, "time_s") : std::nullopt;
}

json optionalNumber(const std::optional<double>& x) { return x ? json(*x) : json(nullptr); }

json cycleNumber(const json& c) {
  const auto n = number(c, "cycle");
  return n ? json(*n == std::round(*n) ? json(static_cast<long long>(*n)) : json(*n)) : json(nullptr);
}

// Rows {time_s, cycle, value, U} of one quantity in one route (cycles without it left out).
json routeRows(const json& eval, const std::string& quantity) {
  json rows = json::array();
  for (const auto& c : array(eval, "cycles")) {
    const auto t = number(c, "time_s");
    const json* v = findValue(c, quantity);
    if (!t || v == nullptr || !number(*v, "value")) continue;
    rows.push_back({{"time_s", *t}, {"cycle", cycleNumber(c)}, {"value", *number(*v, "value")},
                    {"U", optionalNumber(number(*v, "U"))}});
  }
  return rows;
}

// Eq. 7.9 is Eq. 7.3 halved, term by term, from the same four facet changes (parts::ttpErrors:
// (dX1 + dX2 + dY1 + dY2) / 4 against / 2), so its U is half of E_TTP's. Only when the cycle's
// values show exactly that relation (the gauge route's E_TTP is Eq. 7.9 itself): nothing invented.
std::optional<double> eq79U(const json& cycle, double eq79_value) {
  const json* v = findValue(cycle, "ETTP_um");
  if (v == nullptr) return std::nullopt;
  const auto e73 = number(*v, "value"), U73 = number(*v, "U");
  if (!e73 || !U73 || std::abs(eq79_value - *e73 / 2) > 1e-9 * std::max(1.0, std::abs(*e73))) return std::nullopt;
  return *U73 / 2;
}

json alsoRows(const json& eval, const char* key) {
  json rows = json::array();
  for (const auto& c : array(eval, "cycles")) {
    const auto t = number(c, "time_s");
    const auto v = number(object(c, "also"), key);
    if (!t || !v) continue;
    const auto U = std::string(key) == "ETTP_7_9_um" ? eq79U(c, *v) : std::nullopt;
    rows.push_back({{"time_s", *t}, {"cycle", cycleNumber(c)}, {"value", *v}, {"U", U ? json(*U) : json(nullptr)}});
  }
  return rows;
}

constexpr const char* kRTestColumns[] = {"EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"};

RTest readRTest(const std::string& text_in, const std::string& file, const TtpReportOptions& o) {
  RTest r;
  r.file = file;
  r.table = parseCsv(text_in, file);
  r.alpha = o.table_alpha_um_per_m_K;
  r.radius_mm = o.r_test_radius_mm;
  const int tc = r.table.column("time_s");
  if (tc < 0)
    throw InputError(file, r.table.header_line,
                     "the R-test error series has no time_s column (expected the errors.csv of `probeloop evaluate` "
                     "for a sphere artifact: time_s,cycle,EX0C_um,...)");
  bool any = false;
  for (const char* c : kRTestColumns) any |= r.table.column(c) >= 0;
  if (!any)
    throw InputError(file, r.table.header_line,
                     "the R-test error series has none of the columns EX0C_um, EY0C_um, EZ0T_um, ER0T_um, EA0C_urad, "
                     "EB0C_urad, EC0C_urad");
  for (const auto& row : r.table.rows) r.time_s.push_back(r.table.number(row, tc));
  if (!(r.alpha > 0) || !(r.radius_mm > 0) || !std::isfinite(r.alpha) || !std::isfinite(r.radius_mm))
    throw InputError(file, 0, "Eq. 7.10 for the table needs alpha > 0 and R > 0");
  return r;
}

std::optional<double> cell(const CsvTable& t, const CsvRow& row, int col) {
  double v = 0;
  if (!t.tryNumber(row, col, v)) return std::nullopt;
  return v;
}

// One R-test column as drawn beside a quantity: re-referenced to the reference cut when the
// series covers it, then scaled (negated for -E_B0C, 1/(alpha R) for the table's ΔT).
RTestChannel rTestChannel(const RTest& r, const char* column, RTestScale scale) {
  RTestChannel ch;
  const int col = r.table.column(column);
  const int uc = r.table.column(std::string("U_") + column);
  const int cc = r.table.column("cycle");
  if (col < 0) return ch;
  switch (scale) {
    case RTestScale::negated: ch.scale = -1; break;
    case RTestScale::table_temperature: ch.scale = 1.0 / (r.alpha * r.radius_mm * 1e-3); break;
    default: ch.scale = 1;
  }
  struct P {
    double t, v;
    std::optional<double> U, cycle;
  };
  std::vector<P> points;
  for (std::size_t i = 0; i < r.table.rows.size(); ++i) {
    const auto v = cell(r.table, r.table.rows[i], col);
    if (!v) continue;
    points.push_back({r.time_s[i], *v, cell(r.table, r.table.rows[i], uc), cell(r.table, r.table.rows[i], cc)});
  }
  std::stable_sort(points.begin(), points.end(), [](const P& a, const P& b) { return a.t < b.t; });
  if (r.t0 && !points.empty() && *r.t0 >= points.front().t && *r.t0 <= points.back().t) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (points[i].t == *r.t0) {
        ch.offset = points[i].v;
        break;
      }
      if (i + 1 < points.size() && points[i].t < *r.t0 && *r.t0 < points[i + 1].t) {
        const double w = (*r.t0 - points[i].t) / (points[i + 1].t - points[i].t);
        ch.offset = points[i].v + w * (points[i + 1].v - points[i].v);
        break;
      }
    }
    ch.re_referenced = true;
  }
  for (const auto& p : points) {
    json cycle = nullptr;
    if (p.cycle) cycle = *p.cycle == std::round(*p.cycle) ? json(static_cast<long long>(*p.cycle)) : json(*p.cycle);
    ch.rows.push_back({{"time_s", p.t},
                       {"cycle", cycle},
                       {"input", p.v},
                       {"value", ch.scale * (p.v - ch.offset)},
                       {"U", p.U ? json(std::abs(ch.scale) * *p.U) : json(nullptr)}});
  }
  return ch;
}

// Quantities present in a route, known ones first in their order, then others as they come.
std::vector<std::pair<std::string, std::string>> routeQuantities(const json& eval) {
  std::vector<std::pair<std::string, std::string>> out;  // id, unit field
  const auto add = [&out](const std::string& id, const std::string& unit) {
    for (const auto& o : out)
      if (o.first == id) return;
    out.emplace_back(id, unit);
  };
  for (const auto& q : kQuantities)
    for (const auto& c : array(eval, "cycles"))
      if (const json* v = findValue(c, q.id); v && number(*v, "value")) {
        add(q.id, text(*v, "unit"));
        break;
      }
  for (const auto& c : array(eval, "cycles"))
    for (const auto& v : array(c, "values"))
      if (!text(v, "quantity").empty() && number(v, "value")) add(text(v, "quantity"), text(v, "unit"));
  return out;
}

std::string listText(const json& a) {
  std::string s;
  for (const auto& x : a) s += (s.empty() ? "" : ", ") + (x.is_string() ? x.get<std::string>() : x.dump());
  return s;
}

// "seed 004 Eq. 7.1, last term's sign corrected (notes/seed004.md §11 item 10)" ->
// "Blaser 2020 (ETH Diss. 26709), Eq. 7.1, last term's sign corrected".
std::string readerSource(const std::string& source) {
  std::string s = std::regex_replace(source, std::regex(R"(\s*\([^()]*(notes|L[0-9]{3,4})[^()]*\))"), "");
  s = std::regex_replace(s, std::regex(R"(\s*\bnotes/[^ ,;)]+( §[0-9.]+( item [0-9]+)?)?)"), "");
  s = std::regex_replace(s, std::regex(R"(,?\s*\bL[0-9]{3,4}(–L?[0-9]{3,4})?\b)"), "");
  s = std::regex_replace(s, std::regex(R"(\bseed 004\b)"), std::string(kThesis) + ",");
  s = std::regex_replace(s, std::regex(R"(\bseed 000\b)"), "Yaqoob 2017 (MSc thesis, Sabanc\u0131 University),");
  s = std::regex_replace(s, std::regex(R"(,,)"), ",");
  return s;
}

MachineInputs readMachineInputs(const std::string& text_in, const std::string& file) {
  MachineInputs in;
  in.file = file;
  const CsvTable t = parseCsv(text_in, file);
  const int tc = t.column("time_s");
  if (tc < 0)
    throw InputError(file, t.header_line,
                     "the machine's inputs have no time_s column (expected the inputs.csv of `probeloop simulate` or a "
                     "logger: time_s, then one column per signal, temperatures ending in _C, the C axis's speed c_rpm)");
  std::vector<int> temperature_cols;
  int c_rpm = -1;
  for (std::size_t i = 0; i < t.header.size(); ++i) {
    const std::string& name = t.header[i];
    if (name.size() > 2 && name.compare(name.size() - 2, 2, "_C") == 0) temperature_cols.push_back(static_cast<int>(i));
    if (name == "c_rpm") c_rpm = static_cast<int>(i);
  }
  if (temperature_cols.empty() && c_rpm < 0)
    throw InputError(file, t.header_line,
                     "the machine's inputs have no temperature (a column ending in _C) and no C-axis speed (c_rpm)");
  const auto series = [&](int col) {
    InputSeries s{t.header[static_cast<std::size_t>(col)], json::array()};
    for (const auto& row : t.rows) {
      double time = 0, v = 0;
      if (!t.tryNumber(row, tc, time) || !t.tryNumber(row, col, v) || !std::isfinite(time) || !std::isfinite(v)) continue;
      s.rows.push_back({{"time_s", time}, {"value", v}});
    }
    return s;
  };
  for (const int c : temperature_cols) {
    InputSeries s = series(c);
    if (!s.rows.empty()) in.temperatures.push_back(std::move(s));
  }
  if (c_rpm >= 0) {
    InputSeries s = series(c_rpm);
    if (!s.rows.empty()) in.c_rpm = std::move(s);
  }
  return in;
}

}  // namespace probeloop::report::ttp_detail
