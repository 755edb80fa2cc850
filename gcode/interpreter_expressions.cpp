// Expressions and parameters of a run (interpreter_detail.hpp): numbers, #i and #<name>, the
// controller clock's #3011/#3012, Fanuc's #500..#999 as written from outside, functions and
// operators, a word's value, assignments.
#include "gcode/interpreter_detail.hpp"

#include <algorithm>
#include <charconv>
#include <variant>

namespace probeloop::gcode {

double Execution::finite(double v, const Cursor& c, const char* what) const {
  if (std::isfinite(v)) return v;
  fail(std::string(what) + " in '" + c.s + "' gives " + (std::isnan(v) ? "NaN" : "an infinite value") +
       ": not a finite number (overflow); the controller stops here");
}

double Execution::number(Cursor& c) {
  const std::size_t b = c.i;
  while (!c.end() && (std::isdigit(static_cast<unsigned char>(c.peek())) || c.peek() == '.')) ++c.i;
  if (c.i == b) fail("expected a number at column " + std::to_string(b + 1) + " of '" + c.s + "'");
  const std::string_view t(c.s.data() + b, c.i - b);
  if (t == "." || std::count(t.begin(), t.end(), '.') > 1) fail("'" + std::string(t) + "' is not a number");
  // from_chars: correctly rounded like strtod, without the copy and the locale (every number
  // of every expression goes through here, once per execution of its line).
  double v = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec == std::errc::result_out_of_range) {
    // Below the smallest double (0.000...1 with hundreds of zeros): 0, as strtod reads it.
    // Anything with a non-zero digit before the point is above the largest.
    const std::string_view whole = t.substr(0, t.find('.'));
    if (whole.find_first_not_of('0') == std::string_view::npos) return 0.0;
    fail("'" + std::string(t) + "' is too large for a number");
  }
  if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
    fail("'" + std::string(t) + "' is not a finite number");
  return v;
}

double Execution::readParam(Cursor& c) {  // after '#'
  if (c.peek() == '<') {
    const std::size_t close = c.s.find('>', c.i);
    if (close == std::string::npos) fail("named parameter '#<' is not closed");
    const std::string name = c.s.substr(c.i + 1, close - c.i - 1);
    c.i = close + 1;
    const auto it = named_.find(name);
    if (it == named_.end()) fail("named parameter #<" + name + "> is read before it is set");
    return it->second;
  }
  return paramValue(paramNumber(c));
}

double Execution::paramValue(int n) {
  if (in_.dialect_ != ProgramDialect::FanucMacroB) return parameter(n);
  if (n >= 500 && n <= 999) {
    // A retained common variable may have been written from outside since the program last
    // looked (FOCAS cnc_wrmacro): the machine's value, when it has one, is the one read, and
    // stays stored as if it had been written just before this read.
    const auto v = m_.externalVariable(n);
    if (!v) return parameter(n);
    if (!std::isfinite(*v))
      fail("#" + std::to_string(n) + " written from outside is not a finite number; the program cannot use it");
    params_[n] = *v;
    return *v;
  }
  if (n != 3011 && n != 3012) return parameter(n);
  const double s = std::max(0.0, m_.controllerClockS());
  const long days = static_cast<long>(std::floor(s / 86400.0));
  const long sec = static_cast<long>(std::floor(s - 86400.0 * static_cast<double>(days)));
  if (n == 3012) return static_cast<double>(sec / 3600 * 10000 + sec % 3600 / 60 * 100 + sec % 60);
  // Civil date from days since 2026-01-01 (H. Hinnant's days_from_civil, inverted).
  long z = days + 20454 + 719468;  // 2026-01-01 is day 20454 since 1970-01-01
  const long era = z / 146097, doe = z - era * 146097;
  const long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const long doy = doe - (365 * yoe + yoe / 4 - yoe / 100), mp = (5 * doy + 2) / 153;
  const long d = doy - (153 * mp + 2) / 5 + 1, m = mp < 10 ? mp + 3 : mp - 9;
  const long y = yoe + era * 400 + (m <= 2 ? 1 : 0);
  return static_cast<double>(y * 10000 + m * 100 + d);
}

int Execution::paramNumber(Cursor& c) {
  const Nest nest(*this, c.s, c.i);
  const double v = c.peek() == '[' ? bracket(c) : (c.peek() == '#' ? (++c.i, readParam(c)) : number(c));
  const double r = std::round(v);
  if (std::fabs(v - r) > 1e-6 || r < 0 || r > 99999) fail("parameter number " + std::to_string(v) + " is not valid");
  return static_cast<int>(r);
}

double Execution::bracket(Cursor& c) {
  if (!c.take("[")) fail("expected '[' at column " + std::to_string(c.i + 1));
  const double v = expression(c);
  if (!c.take("]")) fail("expected ']' at column " + std::to_string(c.i + 1) + " of '" + c.s + "'");
  return v;
}

double Execution::primary(Cursor& c) {
  const Nest nest(*this, c.s, c.i);
  if (c.take("-")) return -primary(c);
  if (c.take("+")) return primary(c);
  if (c.peek() == '[') return bracket(c);
  if (c.take("#")) return readParam(c);
  if (std::isdigit(static_cast<unsigned char>(c.peek())) || c.peek() == '.') return number(c);
  static const char* functions[] = {"ABS", "ACOS", "ASIN", "ATAN", "COS", "EXP", "FIX", "FUP",
                                    "LN", "ROUND", "SIN", "SQRT", "TAN"};
  for (const char* f : functions) {
    if (c.take(f)) return finite(function(f, c), c, f);
  }
  fail("unexpected '" + std::string(1, c.peek()) + "' at column " + std::to_string(c.i + 1) +
       " of '" + c.s + "' (expected a number, #parameter, [expression] or function)");
}

double Execution::function(const std::string& fn, Cursor& c) {
  const double a = bracket(c);
  if (fn == "ATAN") {
    if (c.take("/")) {
      const double deg = std::atan2(a, bracket(c)) * 180.0 / kPi;
      // Fanuc answers in 0..360, LinuxCNC in -180..180.
      return in_.dialect_ == ProgramDialect::FanucMacroB && deg < 0 ? deg + 360.0 : deg;
    }
    if (in_.dialect_ == ProgramDialect::LinuxCnc) fail("ATAN needs the form ATAN[y]/[x]");
    return std::atan(a) * 180.0 / kPi;
  }
  if (fn == "ABS") return std::fabs(a);
  if (fn == "ACOS" || fn == "ASIN") {
    if (a < -1 || a > 1) fail(fn + " of " + std::to_string(a) + " is undefined");
    return (fn == "ACOS" ? std::acos(a) : std::asin(a)) * 180.0 / kPi;
  }
  if (fn == "COS") return std::cos(a * kPi / 180.0);
  if (fn == "SIN") return std::sin(a * kPi / 180.0);
  if (fn == "TAN") return std::tan(a * kPi / 180.0);
  if (fn == "EXP") return std::exp(a);
  // LinuxCNC rounds down / up; Fanuc truncates toward / away from zero.
  const bool fanuc = in_.dialect_ == ProgramDialect::FanucMacroB;
  if (fn == "FIX") return fanuc ? std::trunc(a) : std::floor(a);
  if (fn == "FUP") return fanuc ? (a < 0 ? std::floor(a) : std::ceil(a)) : std::ceil(a);
  if (fn == "ROUND") return std::round(a);
  if (fn == "LN") {
    if (a <= 0) fail("LN of a non-positive value");
    return std::log(a);
  }
  if (a < 0) fail("SQRT of a negative value");
  return std::sqrt(a);
}

double Execution::power(Cursor& c) {
  double v = primary(c);
  while (c.take("**")) {
    const double e = primary(c);
    if (v < 0 && e != std::floor(e)) fail("a negative number to a non-integer power is undefined");
    v = finite(std::pow(v, e), c, "a power (**)");
  }
  return v;
}

double Execution::product(Cursor& c) {
  double v = power(c);
  for (;;) {
    if (c.s.compare(c.i, 2, "**") != 0 && c.take("*")) v = finite(v * power(c), c, "a product");
    else if (c.take("/")) {
      const double d = power(c);
      if (d == 0) fail("division by zero");
      v = finite(v / d, c, "a quotient");
    } else if (c.take("MOD")) {
      const double d = power(c);
      if (d == 0) fail("MOD by zero");
      v = std::fmod(v, d);  // LinuxCNC: fmod, then made non-negative with |d|
      if (v < 0) v += std::fabs(d);
    } else return v;
  }
}

double Execution::sum(Cursor& c) {
  double v = product(c);
  for (;;) {
    if (c.take("+")) v = finite(v + product(c), c, "a sum");
    else if (c.take("-")) v = finite(v - product(c), c, "a difference");
    else return v;
  }
}

double Execution::comparison(Cursor& c) {
  double v = sum(c);
  for (;;) {
    if (c.take("EQ")) v = v == sum(c);
    else if (c.take("NE")) v = v != sum(c);
    else if (c.take("GT")) v = v > sum(c);
    else if (c.take("GE")) v = v >= sum(c);
    else if (c.take("LT")) v = v < sum(c);
    else if (c.take("LE")) v = v <= sum(c);
    else return v;
  }
}

double Execution::expression(Cursor& c) {
  double v = comparison(c);
  for (;;) {
    // Evaluate the right side first: a short circuit would leave the cursor before it.
    if (c.take("AND")) {
      const double r = comparison(c);
      v = (v != 0) && (r != 0);
    } else if (c.take("OR")) {
      const double r = comparison(c);
      v = (v != 0) || (r != 0);
    } else if (c.take("XOR")) {
      const double r = comparison(c);
      v = (v != 0) != (r != 0);
    }
    else return v;
  }
}

double Execution::wordValue(Cursor& c) {
  if (c.take("-")) return -wordValue(c);
  if (c.take("+")) return wordValue(c);
  if (c.peek() == '[') return bracket(c);
  if (c.take("#")) return readParam(c);
  return number(c);
}

void Execution::assign(const std::string& stmt) {
  Cursor c{stmt, 0};
  std::vector<std::pair<std::variant<int, std::string>, double>> sets;
  while (c.take("#")) {
    std::variant<int, std::string> target;
    if (c.peek() == '<') {
      const auto close = stmt.find('>', c.i);
      if (close == std::string::npos) fail("named parameter '#<' is not closed");
      target = stmt.substr(c.i + 1, close - c.i - 1);
      c.i = close + 1;
    } else {
      target = paramNumber(c);
    }
    if (!c.take("=")) fail("expected '=' after the parameter in '" + stmt + "'");
    sets.push_back({target, expression(c)});
  }
  if (!c.end()) fail("unexpected '" + stmt.substr(c.i) + "' after a parameter assignment");
  for (const auto& [t, v] : sets) {
    if (std::holds_alternative<std::string>(t)) {
      named_[std::get<std::string>(t)] = v;
      continue;
    }
    const int n = std::get<int>(t);
    if (n == 3000 && in_.dialect_ == ProgramDialect::FanucMacroB)
      stop(in_.file_, line_, "program alarm #3000=" + std::to_string(std::lround(v)) +
                                 alarmText(in_.lines_[pc_].comment));
    if (n >= 5000 && n < 6000) fail("parameter #" + std::to_string(n) + " is read-only");
    params_[n] = v;
  }
}

std::string Execution::alarmText(const std::string& comment) {
  return comment.empty() ? "" : " (" + comment + ")";
}

}  // namespace probeloop::gcode
