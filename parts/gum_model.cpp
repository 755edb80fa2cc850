#include "parts/gum_model.hpp"

#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

using uncertainty::Input;

namespace {

Input readInput(YamlMap& in) {
  const std::string name = in.string("name");
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_'))
    in.fail("name", "'" + name + "' must start with a letter or '_' so expressions can use it");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      in.fail("name", "'" + name + "' may contain only letters, digits and '_'");
  if (name == "pi") in.fail("name", "'pi' is the constant pi; choose another name");
  Input x;
  if (in.has("observations")) {
    // Type A (JCGM 100 4.2): the mean, s/sqrt(n), nu = n - 1.
    const auto obs = in.numberList("observations");
    if (obs.size() < 2) in.fail("observations", "a type A evaluation needs at least 2 observations");
    double mean = 0;
    for (double v : obs) mean += v;
    mean /= static_cast<double>(obs.size());
    double ss = 0;
    for (double v : obs) ss += (v - mean) * (v - mean);
    if (ss == 0) in.fail("observations", "all observations are equal: no scatter to evaluate (type A needs s > 0)");
    const double n = static_cast<double>(obs.size());
    const double s_mean = std::sqrt(ss / (n - 1) / n);
    const std::string d = in.stringOr("distribution", "student_t");
    if (d == "student_t") {
      if (obs.size() < 4)
        in.fail("observations", "the scaled t of JCGM 101 6.4.9 needs >= 4 observations for a finite variance; "
                                "give distribution: normal to use s/sqrt(n) as a normal input");
      x = Input::studentT(name, mean, s_mean, n - 1);
    } else if (d == "normal") {
      x = Input::normal(name, mean, s_mean, n - 1);
    } else {
      in.fail("distribution", "observations are student_t (default) or normal, not '" + d + "'");
    }
  } else {
    const double value = in.number("value");
    const std::string d = in.choice("distribution", {"normal", "rectangular", "triangular", "u_shaped", "student_t", "constant"});
    if (d == "normal") {
      const double u = in.number("u");
      if (!(u > 0)) in.fail("u", "the standard uncertainty must be > 0 (use distribution: constant for an exact value)");
      const double dof = in.numberOr("dof", std::numeric_limits<double>::infinity());
      if (!(dof > 0)) in.fail("dof", "degrees of freedom must be > 0");
      x = Input::normal(name, value, u, dof);
      if (in.has("type")) x.type = in.choice("type", {"A", "B"})[0];
    } else if (d == "student_t") {
      const double s = in.number("s");
      if (!(s > 0)) in.fail("s", "the standard deviation of the mean must be > 0");
      const double dof = in.number("dof");
      if (!(dof > 2)) in.fail("dof", "a scaled t needs dof > 2 for a finite standard deviation (JCGM 101 6.4.9)");
      x = Input::studentT(name, value, s, dof);
    } else if (d == "constant") {
      x = Input::normal(name, value, 0.0);
      x.type = 'B';
    } else {
      const double a = in.number("half_width");
      if (!(a > 0)) in.fail("half_width", "the half-width must be > 0");
      x = d == "rectangular" ? Input::rectangular(name, value, a)
          : d == "triangular" ? Input::triangular(name, value, a)
                              : Input::uShaped(name, value, a);
    }
  }
  x.unit = in.stringOr("unit", "");
  in.stringOr("basis", "");  // documentation only
  in.finish();
  return x;
}

// The offending line of the file with a caret, when the expression sits on that line.
std::string caret(const std::string& file_text, int line, int file_column, const std::string& expr, int expr_column,
                  bool& on_file_line) {
  std::istringstream in(file_text);
  std::string l;
  for (int i = 0; i < line && std::getline(in, l); ++i) {
  }
  std::ostringstream o;
  if (expr.find('\n') != std::string::npos) {  // a block scalar: show the expression's own line
    on_file_line = false;
    std::size_t start = 0, col = static_cast<std::size_t>(expr_column - 1);
    int l_no = 1;
    for (std::size_t k = 0; k < col && k < expr.size(); ++k)
      if (expr[k] == '\n') start = k + 1, ++l_no;
    const std::size_t end = expr.find('\n', start);
    o << " (line " << l_no << " of the expression)\n  " << expr.substr(start, end == std::string::npos ? end : end - start)
      << "\n  " << std::string(col - start, ' ') << "^";
    return o.str();
  }
  on_file_line = file_column > 0 && static_cast<std::size_t>(file_column - 1) <= l.size() &&
                 l.compare(static_cast<std::size_t>(file_column - 1), expr.size(), expr) == 0;
  if (on_file_line) {
    o << "\n  " << l << "\n  " << std::string(static_cast<std::size_t>(file_column - 1 + expr_column - 1), ' ') << "^";
  } else {
    o << "\n  " << expr << "\n  " << std::string(static_cast<std::size_t>(expr_column - 1), ' ') << "^";
  }
  return o.str();
}

}  // namespace

uncertainty::TextModel loadGumModel(const std::string& path) {
  const std::string text = readFile(path, kYamlInput);  // read once: the carets quote its lines
  YamlMap root(loadYamlText(text, path), path, "");
  root.choice("kind", {"gum_model"});
  uncertainty::TextModel m;
  m.file = path;
  m.title = root.stringOr("title", "");
  m.p = root.numberOr("coverage_probability", 0.95);
  if (!(m.p > 0 && m.p < 1)) root.fail("coverage_probability", "expected a probability in (0, 1), e.g. 0.95");

  std::map<std::string, std::size_t> index;
  std::vector<std::vector<double>> observations;
  for (auto& in : root.mapList("inputs")) {
    const int line = in.line();
    observations.push_back(in.has("observations") ? in.numberList("observations") : std::vector<double>{});
    Input x = readInput(in);
    if (index.count(x.name)) throw InputError(path, line, "inputs: '" + x.name + "' is defined twice");
    index[x.name] = m.inputs.inputs.size();
    m.inputs.inputs.push_back(std::move(x));
  }
  std::vector<std::string> names;
  for (const auto& in : m.inputs.inputs) names.push_back(in.name);

  const auto n = static_cast<Eigen::Index>(names.size());
  if (root.booleanOr("correlate_observations", false)) {
    // JCGM 100 5.2.3, Eq. (17): r from simultaneous observations of equal number.
    m.inputs.correlation = Eigen::MatrixXd::Identity(n, n);
    auto mean = [](const std::vector<double>& v) {
      double s = 0;
      for (double x : v) s += x;
      return s / static_cast<double>(v.size());
    };
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = i + 1; j < n; ++j) {
        const auto& a = observations[static_cast<std::size_t>(i)];
        const auto& b = observations[static_cast<std::size_t>(j)];
        if (a.empty() || b.empty()) continue;
        if (a.size() != b.size())
          root.fail("correlate_observations", "inputs " + names[static_cast<std::size_t>(i)] + " and " +
                                                  names[static_cast<std::size_t>(j)] + " have " + std::to_string(a.size()) +
                                                  " and " + std::to_string(b.size()) +
                                                  " observations; simultaneous observations come in equal numbers");
        const double ma = mean(a), mb = mean(b);
        double sab = 0, saa = 0, sbb = 0;
        for (std::size_t k = 0; k < a.size(); ++k) {
          sab += (a[k] - ma) * (b[k] - mb);
          saa += (a[k] - ma) * (a[k] - ma);
          sbb += (b[k] - mb) * (b[k] - mb);
        }
        if (saa > 0 && sbb > 0) m.inputs.correlation(i, j) = m.inputs.correlation(j, i) = sab / std::sqrt(saa * sbb);
      }
  }
  if (root.has("correlations")) {
    const YAML::Node list = root.raw("correlations");
    if (!list.IsSequence()) root.fail("correlations", "expected a list of [input, input, r]");
    if (m.inputs.correlation.size() == 0) m.inputs.correlation = Eigen::MatrixXd::Identity(n, n);
    std::set<std::pair<std::size_t, std::size_t>> given;
    for (const auto& item : list) {
      const int line = item.Mark().line + 1;
      if (!item.IsSequence() || item.size() != 3 || !item[0].IsScalar() || !item[1].IsScalar() || !item[2].IsScalar())
        throw InputError(path, line, "correlations: each entry is [input, input, r], e.g. [V, I, -0.36]");
      const std::string a = item[0].Scalar(), b = item[1].Scalar();
      double r = 0;
      if (!parseFiniteNumber(item[2].Scalar(), r) || std::fabs(r) > 1)
        throw InputError(path, line, "correlations: r must be a number in [-1, 1]");
      for (const auto& s : {a, b})
        if (!index.count(s)) throw InputError(path, line, "correlations: unknown input '" + s + "'");
      if (a == b) throw InputError(path, line, "correlations: an input is correlated with itself by definition (r = 1)");
      const auto i = static_cast<Eigen::Index>(index[a]), j = static_cast<Eigen::Index>(index[b]);
      if (!given.insert({std::min(index[a], index[b]), std::max(index[a], index[b])}).second)
        throw InputError(path, line, "correlations: r(" + a + ", " + b + ") is given twice");
      m.inputs.correlation(i, j) = m.inputs.correlation(j, i) = r;
    }
  }
  try {
    m.inputs.check();
  } catch (const InputError& e) {
    throw InputError(path, root.has("correlations") ? root.line("correlations") : root.line("inputs"), e.what());
  }

  std::set<std::string> output_names;
  for (auto& out : root.mapList("outputs")) {
    uncertainty::TextOutput o;
    o.name = out.string("name");
    if (o.name.empty()) out.fail("name", "an output needs a name");
    if (!output_names.insert(o.name).second) out.fail("name", "output '" + o.name + "' is defined twice");
    o.unit = out.stringOr("unit", "");
    const std::string expr = out.string("model");
    o.line = out.line("model");
    try {
      o.model = uncertainty::Expression::parse(expr, names);
    } catch (const uncertainty::ExpressionError& e) {
      const int fc = out.textColumn("model");
      std::ostringstream msg;
      msg << "outputs." << o.name << ".model: " << e.what();
      bool on_file_line = false;
      const std::string c = caret(text, out.line("model"), fc, expr, e.column(), on_file_line);
      if (on_file_line) msg << " (file column " << fc + e.column() - 1 << ")";
      msg << c;
      throw InputError(path, out.line("model"), msg.str());
    }
    out.finish();
    m.outputs.push_back(std::move(o));
  }
  root.finish();
  return m;
}

}  // namespace probeloop::parts
