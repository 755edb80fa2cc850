#include "gcode/interpreter.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <memory>
#include <optional>
#include <set>
#include <string_view>
#include <variant>
#include <algorithm>

#include "core/error.hpp"

namespace probeloop::gcode {

namespace {

constexpr double kPi = std::numbers::pi;

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}
std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Messages that act (LinuxCNC active comments); other comments are ignored.
bool isActiveComment(const std::string& body, ProgramDialect d) {
  if (d != ProgramDialect::LinuxCnc) return false;
  const std::string u = upper(body);
  for (const char* k : {"LOGOPEN", "LOGAPPEND", "LOGCLOSE", "LOG", "ABORT", "MSG", "DEBUG", "PRINT"}) {
    const std::string key = k;
    if (u.compare(0, key.size(), key) == 0 &&
        (u.size() == key.size() || u[key.size()] == ',' || key == "LOGCLOSE"))
      return true;
  }
  return false;
}

// A small non-negative integer written in the program (labels, loop numbers, parameter
// numbers); nullopt when it is not one.
std::optional<int> smallInt(const std::string& digits) {
  if (digits.empty() || digits.size() > 6) return std::nullopt;
  for (char c : digits)
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  return std::stoi(digits);
}

// An error raised by the program itself (alarm, ABORT, probe without contact): the
// controller stops there.
[[noreturn]] void stop(const std::string& file, int line, const std::string& what) {
  throw SafetyError(file + ":" + std::to_string(line) + ": " + what);
}

}  // namespace

Interpreter::Interpreter(ProgramDialect dialect, std::string file_name, const std::string& text)
    : dialect_(dialect), file_(std::move(file_name)) {
  int number = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string raw = text.substr(start, end - start);
    ++number;
    start = end + 1;
    if (!raw.empty() && raw.back() == '\r') raw.pop_back();
    Line l;
    l.number = number;
    bool in_name = false;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const char c = raw[i];
      if (c == '(') {
        const std::size_t close = raw.find(')', i);
        if (close == std::string::npos)
          throw InputError(file_, number, "comment '(' is not closed on this line");
        const std::string body = raw.substr(i + 1, close - i - 1);
        l.comment = body;
        if (isActiveComment(body, dialect_)) {
          if (!l.message.empty())
            throw InputError(file_, number, "two active comments on one line; the simulator takes one");
          l.message = body;
        }
        i = close;
        continue;
      }
      if (c == ';' && dialect_ == ProgramDialect::LinuxCnc) break;
      if (std::isspace(static_cast<unsigned char>(c))) continue;
      if (c == '<') in_name = true;
      if (c == '>') in_name = false;
      l.code += in_name ? static_cast<char>(std::tolower(static_cast<unsigned char>(c)))
                        : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    if (l.code == "%") l.code.clear();  // Fanuc tape start/end
    if (!l.code.empty() || !l.message.empty()) lines_.push_back(l);
    if (end == text.size()) break;
  }
}

double Interpreter::parameter(int number) const {
  const auto it = params_.find(number);
  return it == params_.end() ? 0.0 : it->second;
}
double Interpreter::namedParameter(const std::string& name) const {
  const auto it = named_.find(lower(name));
  return it == named_.end() ? 0.0 : it->second;
}

// One run of the program: cursor, modal state and control flow.
class Execution {
 public:
  Execution(Interpreter& in, MachineInterface& m, ProbeBranching* branching)
      : in_(in), m_(m), params_(in.params_), named_(in.named_), branching_(branching), pos_(m.start()) {}

  InterpreterResult run(long max_blocks) {
    buildJumps();
    max_blocks_ = max_blocks;
    return runFrom(0);
  }

  // The parameters as the run left them (for Interpreter::parameter).
  void publishParameters() const {
    in_.params_ = params_;
    in_.named_ = named_;
  }

 private:
  InterpreterResult runFrom(std::size_t start) {
    InterpreterResult r;
    pc_ = start;
    while (pc_ < in_.lines_.size()) {
      if (++blocks_ > max_blocks_)
        fail("the program executed " + std::to_string(max_blocks_) +
             " blocks without ending; an endless loop?");
      r.blocks_executed = blocks_;
      const auto& line = in_.lines_[pc_];
      line_ = line.number;
      m_.atLine(line_);
      std::size_t next = pc_ + 1;
      try {
        if (executeLine(line, next)) {
          r.ended = true;
          return r;
        }
      } catch (const SafetyError& e) {
        const std::string w = e.what();
        if (w.rfind(in_.file_ + ":", 0) == 0) throw;
        throw SafetyError(in_.file_ + ":" + std::to_string(line_) + ": " + w);
      } catch (const InputError& e) {
        if (e.line() > 0 && e.file() == in_.file_) throw;
        fail(e.what());
      }
      pc_ = next;
    }
    r.blocks_executed = blocks_;
    return r;
  }

  Interpreter& in_;
  MachineInterface& m_;
  // Parameters of this run (a probe branch has its own copy): numbered and named.
  std::map<int, double> params_;
  std::map<std::string, double> named_;
  double parameter(int n) const {
    const auto it = params_.find(n);
    return it == params_.end() ? 0.0 : it->second;
  }
  ProbeBranching* branching_ = nullptr;
  long max_blocks_ = Interpreter::kMaxBlocks;
  long blocks_ = 0;       // blocks executed so far (a branch goes on counting)
  bool line_ends_ = false;  // M2/M30 on the line being executed
  std::size_t pc_ = 0;
  int line_ = 0;

  // Modal state.
  double motion_ = 0;  // 0, 1, 2, 3, 38.2, 38.3, 80 (none)
  bool absolute_ = true;
  double feed_ = 0;
  int wcs_ = 1;
  std::array<std::array<double, 5>, 7> offsets_{};  // [1..6] x y z b c
  double tool_length_ = 0;
  int tool_in_spindle_ = 0, tool_selected_ = 0;
  double spindle_rpm_ = 0;
  int spindle_dir_ = 0;  // +1 M3, -1 M4, 0 stopped
  MachinePosition pos_;  // gauge line, machine coordinates
  bool log_open_ = false;
  bool seen_program_number_ = false;

  // Control flow.
  // Resolved once per run, before it starts; a probe branch shares them.
  struct Control {
    std::map<std::size_t, std::size_t> jump;       // line index -> matching end / next branch
    std::map<std::size_t, std::size_t> loop_back;  // end of loop -> its head
    std::map<int, std::size_t> labels;             // Fanuc N labels
    std::map<std::size_t, std::size_t> endif_of;   // elseif/else line -> its endif
  };
  std::shared_ptr<Control> control_;

  [[noreturn]] void fail(const std::string& m) const { throw InputError(in_.file_, line_, m); }


  // ---------------------------------------------------------------------------------
  // Expressions

  // The expression reader recurses per bracket, unary sign and '#' of an indirect parameter
  // (##1); without a bound, "[[[[..." of a few thousand levels exhausted the stack (found by
  // fuzz/gcode_linuxcnc_fuzz). LinuxCNC's lines are at most 256 characters; 100 levels is far
  // more than any program needs.
  static constexpr int kMaxNesting = 100;
  int nesting_ = 0;
  struct Nest {
    Nest(Execution& e, const std::string& line, std::size_t column) : e_(e) {
      if (++e_.nesting_ > kMaxNesting) {
        --e_.nesting_;  // a constructor that throws gets no destructor call
        e_.fail("expression nested more than " + std::to_string(kMaxNesting) + " levels deep (brackets, signs or #) at column " +
                std::to_string(column + 1) + " of '" + line.substr(0, 60) + (line.size() > 60 ? "...'" : "'"));
      }
    }
    ~Nest() { --e_.nesting_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;
    Execution& e_;
  };

  struct Cursor {
    const std::string& s;
    std::size_t i = 0;
    bool end() const { return i >= s.size(); }
    char peek() const { return end() ? '\0' : s[i]; }
    // Called for every operator and keyword tried at every position of every expression
    // evaluated: the first character decides most calls without a compare.
    bool take(std::string_view t) {
      if (i >= s.size() || s[i] != t.front()) return false;
      if (s.compare(i, t.size(), t) == 0) {
        i += t.size();
        return true;
      }
      return false;
    }
  };

  // Every value the program computes must be a finite number: an overflow (EXP[1000],
  // [1e300*1e300]) or what follows from one (inf - inf = NaN) stops the program here, as a
  // controller stops with a calculation-overflow alarm. A NaN let through would compare false
  // with every limit and a move to it could pass any check (issue 28).
  double finite(double v, const Cursor& c, const char* what) const {
    if (std::isfinite(v)) return v;
    fail(std::string(what) + " in '" + c.s + "' gives " + (std::isnan(v) ? "NaN" : "an infinite value") +
         ": not a finite number (overflow); the controller stops here");
  }

  double number(Cursor& c) {
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

  double readParam(Cursor& c) {  // after '#'
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

  // A numbered parameter; Fanuc's #3011 (date YYYYMMDD) and #3012 (time HHMMSS) read the
  // controller's clock.
  double paramValue(int n) {
    if (in_.dialect_ != ProgramDialect::FanucMacroB || (n != 3011 && n != 3012)) return parameter(n);
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

  int paramNumber(Cursor& c) {
    const Nest nest(*this, c.s, c.i);
    const double v = c.peek() == '[' ? bracket(c) : (c.peek() == '#' ? (++c.i, readParam(c)) : number(c));
    const double r = std::round(v);
    if (std::fabs(v - r) > 1e-6 || r < 0 || r > 99999) fail("parameter number " + std::to_string(v) + " is not valid");
    return static_cast<int>(r);
  }

  double bracket(Cursor& c) {
    if (!c.take("[")) fail("expected '[' at column " + std::to_string(c.i + 1));
    const double v = expression(c);
    if (!c.take("]")) fail("expected ']' at column " + std::to_string(c.i + 1) + " of '" + c.s + "'");
    return v;
  }

  double primary(Cursor& c) {
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

  // A function's value, after its name.
  double function(const std::string& fn, Cursor& c) {
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

  double power(Cursor& c) {
    double v = primary(c);
    while (c.take("**")) {
      const double e = primary(c);
      if (v < 0 && e != std::floor(e)) fail("a negative number to a non-integer power is undefined");
      v = finite(std::pow(v, e), c, "a power (**)");
    }
    return v;
  }
  double product(Cursor& c) {
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
  double sum(Cursor& c) {
    double v = product(c);
    for (;;) {
      if (c.take("+")) v = finite(v + product(c), c, "a sum");
      else if (c.take("-")) v = finite(v - product(c), c, "a difference");
      else return v;
    }
  }
  double comparison(Cursor& c) {
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
  double expression(Cursor& c) {
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

  // A word's value: a number, a parameter, or a bracketed expression, with a sign.
  double wordValue(Cursor& c) {
    if (c.take("-")) return -wordValue(c);
    if (c.take("+")) return wordValue(c);
    if (c.peek() == '[') return bracket(c);
    if (c.take("#")) return readParam(c);
    return number(c);
  }

  // ---------------------------------------------------------------------------------
  // Control structures, resolved once before running.

  struct OWord {
    std::string label, keyword;
    std::size_t rest = 0;  // index in code after the keyword
  };
  std::optional<OWord> oword(const std::string& code) const {
    if (in_.dialect_ != ProgramDialect::LinuxCnc || code.empty() || code[0] != 'O') return std::nullopt;
    std::size_t i = 1;
    if (i < code.size() && code[i] == '<') {
      i = code.find('>', i);
      if (i == std::string::npos) return std::nullopt;
      ++i;
    } else {
      while (i < code.size() && std::isdigit(static_cast<unsigned char>(code[i]))) ++i;
    }
    OWord o;
    o.label = code.substr(1, i - 1);
    std::size_t k = i;
    while (k < code.size() && std::isalpha(static_cast<unsigned char>(code[k]))) ++k;
    o.keyword = code.substr(i, k - i);
    o.rest = k;
    return o;
  }

  void buildJumps() {
    control_ = std::make_shared<Control>();
    const auto& L = in_.lines_;
    std::vector<std::pair<std::string, std::size_t>> stack;  // keyword@label, line index
    std::map<std::size_t, std::vector<std::size_t>> branches;  // if -> elseif/else lines
    std::vector<std::pair<int, std::size_t>> fanuc_do;
    for (std::size_t k = 0; k < L.size(); ++k) {
      line_ = L[k].number;
      const std::string& code = L[k].code;
      if (auto o = oword(code)) {
        static const std::vector<std::string> unsupported{"SUB", "ENDSUB", "CALL", "RETURN",
                                                          "REPEAT", "ENDREPEAT", "DO", "BREAK", "CONTINUE"};
        for (const auto& u : unsupported)
          if (o->keyword == u)
            fail("o-word '" + lower(u) + "' is not modelled by the simulator (supported: while, "
                 "endwhile, if, elseif, else, endif)");
        if (o->keyword == "WHILE" || o->keyword == "IF") {
          stack.push_back({o->keyword + "@" + o->label, k});
        } else if (o->keyword == "ELSEIF" || o->keyword == "ELSE") {
          if (stack.empty() || stack.back().first != "IF@" + o->label)
            fail("o" + lower(o->label) + " " + lower(o->keyword) + " without a matching if");
          branches[stack.back().second].push_back(k);
        } else if (o->keyword == "ENDWHILE" || o->keyword == "ENDIF") {
          const std::string want = (o->keyword == "ENDWHILE" ? "WHILE@" : "IF@") + o->label;
          if (stack.empty() || stack.back().first != want)
            fail("o" + lower(o->label) + " " + lower(o->keyword) + " without a matching " +
                 (o->keyword == "ENDWHILE" ? "while" : "if"));
          const std::size_t head = stack.back().second;
          stack.pop_back();
          if (o->keyword == "ENDWHILE") {
            control_->jump[head] = k;
            control_->loop_back[k] = head;
          } else {
            // Chain: if -> first branch -> next branch ... -> endif; each branch's end jumps
            // to endif (recorded as the branch line -> endif in loop_back_ with a marker).
            std::size_t prev = head;
            for (std::size_t b : branches[head]) {
              control_->jump[prev] = b;
              prev = b;
            }
            control_->jump[prev] = k;
            for (std::size_t b : branches[head]) control_->endif_of[b] = k;
          }
        } else {
          fail("o-word keyword '" + lower(o->keyword) + "' is not modelled by the simulator");
        }
        continue;
      }
      if (in_.dialect_ == ProgramDialect::FanucMacroB) {
        std::size_t i = 0;
        if (code[0] == 'N') {
          i = 1;
          while (i < code.size() && std::isdigit(static_cast<unsigned char>(code[i]))) ++i;
          if (i > 1) {
            const auto parsed = smallInt(code.substr(1, i - 1));
            if (!parsed) fail("label N" + code.substr(1, i - 1) + " is not a number of at most 6 digits");
            const int n = *parsed;
            if (control_->labels.count(n)) fail("label N" + std::to_string(n) + " appears twice");
            control_->labels[n] = k;
          }
        }
        const std::string rest = code.substr(i);
        if (rest.rfind("WHILE", 0) == 0) {
          const std::size_t d = rest.rfind("DO");
          if (d == std::string::npos) fail("WHILE without DOm");
          const auto m = smallInt(rest.substr(d + 2));
          if (!m || *m < 1 || *m > 3) fail("WHILE [..] DOm needs m = 1, 2 or 3");
          fanuc_do.push_back({*m, k});
        } else if (rest.rfind("END", 0) == 0 && rest.size() > 3 &&
                   std::isdigit(static_cast<unsigned char>(rest[3]))) {
          const auto parsed = smallInt(rest.substr(3));
          if (!parsed) fail("END" + rest.substr(3) + ": expected ENDm with m = 1, 2 or 3");
          const int m = *parsed;
          if (fanuc_do.empty() || fanuc_do.back().first != m)
            fail("END" + std::to_string(m) + " without a matching WHILE ... DO" + std::to_string(m));
          control_->jump[fanuc_do.back().second] = k;
          control_->loop_back[k] = fanuc_do.back().second;
          fanuc_do.pop_back();
        }
      }
    }
    if (!stack.empty()) {
      line_ = L[stack.back().second].number;
      fail("this block is never closed (" + lower(stack.back().first) + ")");
    }
    if (!fanuc_do.empty()) {
      line_ = L[fanuc_do.back().second].number;
      fail("WHILE ... DO" + std::to_string(fanuc_do.back().first) + " is never closed by END");
    }
  }

  // Returns true when the program ends.
  bool executeLine(const Interpreter::Line& line, std::size_t& next) {
    if (!line.message.empty()) activeComment(line.message);
    const std::string& code = line.code;
    if (code.empty()) return false;
    if (auto o = oword(code)) return controlLinux(*o, code, next), false;
    if (in_.dialect_ == ProgramDialect::FanucMacroB) {
      std::size_t i = 0;
      if (code[0] == 'N') {
        i = 1;
        while (i < code.size() && std::isdigit(static_cast<unsigned char>(code[i]))) ++i;
      }
      const std::string rest = code.substr(i);
      if (rest.empty()) return false;
      if (rest[0] == 'O') {
        // The program number; a second one would start another program (a subprogram).
        if (seen_program_number_) fail("a second program number '" + rest + "': subprograms are not modelled");
        seen_program_number_ = true;
        return false;
      }
      if (controlFanuc(rest, next)) return false;
      return block(rest);
    }
    return block(code);
  }

  void controlLinux(const OWord& o, const std::string& code, std::size_t& next) {
    Cursor c{code, o.rest};
    const auto k = pc_;
    if (o.keyword == "WHILE") {
      if (!condition(c)) next = control_->jump.at(k) + 1;
    } else if (o.keyword == "ENDIF") {
      // Reached by falling out of the last branch or by a jump: nothing to do.
    } else if (o.keyword == "ENDWHILE") {
      next = control_->loop_back.at(k);
    } else if (o.keyword == "IF") {
      if (!condition(c)) {
        next = control_->jump.at(k);  // to the first elseif/else or the endif
        branch_target_ = next;
      }
    } else if (o.keyword == "ELSEIF" || o.keyword == "ELSE") {
      // Reached by a jump from a failed condition: test this branch. Reached by falling
      // out of a taken branch: skip to the endif.
      if (branch_target_ == k) {
        branch_target_ = kNone;
        if (o.keyword == "ELSE" || condition(c)) return;
        next = control_->jump.at(k);
        branch_target_ = next;
        return;
      }
      next = control_->endif_of.at(k);
    }
  }
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t branch_target_ = kNone;

  bool condition(Cursor& c) {
    if (c.peek() != '[') fail("expected a [condition]");
    const double v = bracket(c);
    if (!c.end()) fail("unexpected '" + c.s.substr(c.i) + "' after the condition");
    return v != 0;
  }

  // Fanuc control words; true when the line was one.
  bool controlFanuc(const std::string& rest, std::size_t& next) {
    Cursor c{rest, 0};
    if (c.take("WHILE")) {
      const double v = bracket(c);
      if (!c.take("DO")) fail("WHILE [..] must be followed by DOm");
      if (v == 0) next = control_->jump.at(pc_) + 1;
      return true;
    }
    if (c.take("END") && !c.end() && std::isdigit(static_cast<unsigned char>(c.peek()))) {
      next = control_->loop_back.at(pc_);
      return true;
    }
    c.i = 0;
    if (c.take("GOTO")) {
      next = label(static_cast<int>(std::lround(wordValue(c))));
      return true;
    }
    if (c.take("IF")) {
      const double v = bracket(c);
      if (c.take("GOTO")) {
        const int n = static_cast<int>(std::lround(wordValue(c)));
        if (v != 0) next = label(n);
        return true;
      }
      if (c.take("THEN")) {
        if (v != 0) {
          const std::string stmt = rest.substr(c.i);
          if (stmt.empty() || stmt[0] != '#') fail("IF ... THEN takes an assignment (#i=...)");
          assign(stmt);
        }
        return true;
      }
      fail("IF [..] must be followed by GOTO n or THEN");
    }
    if (rest == "POPEN") {
      m_.openLog("");
      m_.log("%");
      log_open_ = true;
      return true;
    }
    if (rest == "PCLOS") {
      if (log_open_) m_.log("%");
      m_.closeLog();
      log_open_ = false;
      return true;
    }
    if (rest.rfind("DPRNT[", 0) == 0) {
      if (!log_open_) fail("DPRNT before POPEN");
      if (rest.back() != ']') fail("DPRNT[ is not closed by ]");
      m_.log(dprnt(rest.substr(6, rest.size() - 7)));
      return true;
    }
    if (rest.rfind("M98", 0) == 0 || rest.rfind("M99", 0) == 0 || rest.rfind("G65", 0) == 0)
      fail("subprogram calls (M98/M99/G65) are not modelled by the simulator");
    return false;
  }

  std::size_t label(int n) {
    const auto it = control_->labels.find(n);
    if (it == control_->labels.end()) fail("GOTO " + std::to_string(n) + ": no block N" + std::to_string(n));
    return it->second;
  }

  // Fanuc DPRNT: letters as they are, '*' = space, #i[ab] = value with a integer and b
  // decimal digits (sign column first).
  std::string dprnt(const std::string& body) {
    std::string out;
    Cursor c{body, 0};
    while (!c.end()) {
      if (c.take("*")) {
        out += ' ';
      } else if (c.take("#")) {
        const double v = paramValue(paramNumber(c));
        if (!c.take("[")) fail("DPRNT #i needs a format [ab]");
        const std::size_t close = body.find(']', c.i);
        if (close == std::string::npos || close - c.i != 2) fail("DPRNT format must be [ab], two digits");
        const int a = body[c.i] - '0', b = body[c.i + 1] - '0';
        c.i = close + 1;
        char buf[64];
        if (b == 0) std::snprintf(buf, sizeof buf, "%*ld", a + 1, std::lround(v));
        else std::snprintf(buf, sizeof buf, "%*.*f", a + 2 + b, b, v);
        out += buf;
      } else {
        out += c.peek();
        ++c.i;
      }
    }
    return out;
  }

  // LinuxCNC active comments.
  void activeComment(const std::string& body) {
    const std::string u = upper(body);
    const auto comma = body.find(',');
    const std::string text = comma == std::string::npos ? "" : body.substr(comma + 1);
    if (u.rfind("LOGOPEN", 0) == 0 || u.rfind("LOGAPPEND", 0) == 0) {
      m_.openLog(text);
      log_open_ = true;
    } else if (u.rfind("LOGCLOSE", 0) == 0) {
      m_.closeLog();
      log_open_ = false;
    } else if (u.rfind("LOG", 0) == 0) {
      if (log_open_) m_.log(substitute(text));
    } else if (u.rfind("ABORT", 0) == 0) {
      stop(in_.file_, line_, "program aborted: " + substitute(text));
    }
    // MSG, DEBUG, PRINT: operator messages, no effect on the machine.
  }

  // LinuxCNC substitutes #n and #<name> in LOG text with "%lf" and nothing else.
  std::string substitute(const std::string& text) {
    std::string out;
    for (std::size_t i = 0; i < text.size();) {
      if (text[i] == '#' && i + 1 < text.size()) {
        if (text[i + 1] == '<') {
          const auto close = text.find('>', i);
          if (close != std::string::npos) {
            std::string name;
            for (std::size_t k = i + 2; k < close; ++k)
              if (!std::isspace(static_cast<unsigned char>(text[k])))
                name += static_cast<char>(std::tolower(static_cast<unsigned char>(text[k])));
            const auto it = named_.find(name);
            if (it == named_.end()) fail("LOG names #<" + name + ">, which is not set");
            out += fmtLf(it->second);
            i = close + 1;
            continue;
          }
        } else if (std::isdigit(static_cast<unsigned char>(text[i + 1]))) {
          std::size_t k = i + 1;
          while (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) ++k;
          const auto n = smallInt(text.substr(i + 1, k - i - 1));
          if (!n) fail("LOG names #" + text.substr(i + 1, k - i - 1) + ", which is not a parameter number");
          out += fmtLf(parameter(*n));
          i = k;
          continue;
        }
      }
      out += text[i++];
    }
    return out;
  }
  static std::string fmtLf(double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%f", v);
    return b;
  }

  // #i=expr, #<name>=expr (LinuxCNC allows several on a line; values are read first).
  void assign(const std::string& stmt) {
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
  static std::string alarmText(const std::string& comment) {
    return comment.empty() ? "" : " (" + comment + ")";
  }

  // ---------------------------------------------------------------------------------
  // Ordinary blocks

  struct Words {
    std::vector<double> g, m;
    std::map<char, double> v;
    std::set<char> used;
    bool has(char k) const { return v.count(k) > 0; }
    double take(char k) {
      used.insert(k);
      return v.at(k);
    }
  };

  bool block(const std::string& code) {
    if (code[0] == '#') {
      assign(code);
      return false;
    }
    if (code[0] == '/') fail("block delete '/' is not modelled by the simulator");
    Words w;
    Cursor c{code, 0};
    while (!c.end()) {
      const char letter = c.peek();
      if (!std::isalpha(static_cast<unsigned char>(letter)))
        fail("expected a word letter at column " + std::to_string(c.i + 1) + " of '" + code + "'");
      ++c.i;
      if (c.peek() == '=') fail("unexpected '=' in '" + code + "'");
      const std::size_t value_at = c.i;
      const double v = wordValue(c);
      static const std::string lengths = "XYZBCIJR";
      if (in_.dialect_ == ProgramDialect::FanucMacroB && lengths.find(letter) != std::string::npos && v != 0 &&
          code.substr(value_at, c.i - value_at).find_first_of(".#[") == std::string::npos)
        fail(std::string("'") + letter + code.substr(value_at, c.i - value_at) +
             "' has no decimal point: a Fanuc control reads it in least input increments (um), "
             "not mm; write it with a point");
      if (letter == 'G') w.g.push_back(std::round(v * 10) / 10);
      else if (letter == 'M') w.m.push_back(v);
      else if (letter == 'N') continue;
      else {
        static const std::string allowed = "XYZBCFSTHPLIJR";
        if (allowed.find(letter) == std::string::npos)
          fail("word '" + std::string(1, letter) + "' is not modelled by the simulator");
        if (w.v.count(letter)) fail("word '" + std::string(1, letter) + "' appears twice");
        w.v[letter] = v;
      }
    }
    return execute(w);
  }

  static bool isG(double g, double want) { return std::fabs(g - want) < 1e-6; }

  // A word that must be a whole number in a sane range (tool, offset, P of G10...).
  int wholeWord(Words& w, char k, int lo, int hi) {
    const double v = w.take(k);
    if (!(v >= lo && v <= hi) || std::fabs(v - std::round(v)) > 1e-9)
      fail(std::string(1, k) + formatG(v) + ": expected a whole number " + std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(std::lround(v));
  }
  static std::string formatG(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
  }

  bool execute(Words& w) {
    bool g53 = false, g31 = false, g10 = false, g4 = false, g43 = false;
    std::optional<double> motion;
    for (double g : w.g) {
      if (isG(g, 0) || isG(g, 1) || isG(g, 2) || isG(g, 3)) motion = g;
      else if (isG(g, 80) && in_.dialect_ == ProgramDialect::LinuxCnc) motion = g;
      else if (isG(g, 80)) {
      }  // Fanuc: cancels canned cycles only; none are modelled
      else if ((isG(g, 38.2) || isG(g, 38.3)) && in_.dialect_ == ProgramDialect::LinuxCnc) motion = g;
      else if (isG(g, 31) && in_.dialect_ == ProgramDialect::FanucMacroB) g31 = true;
      else if (isG(g, 90)) absolute_ = true;
      else if (isG(g, 91)) absolute_ = false;
      else if (isG(g, 21) || isG(g, 17) || isG(g, 40) || isG(g, 94)) {
      } else if (isG(g, 20)) fail("G20 (inch) is not modelled by the simulator; the planner writes G21");
      else if (isG(g, 18) || isG(g, 19)) fail("planes other than G17 are not modelled by the simulator");
      else if (isG(g, 49)) tool_length_ = 0;
      else if (isG(g, 43)) g43 = true;
      else if (isG(g, 53)) g53 = true;
      else if (g >= 54 - 1e-6 && g <= 59 + 1e-6 && isG(g, std::round(g))) wcs_ = static_cast<int>(std::lround(g)) - 53;
      else if (isG(g, 10)) g10 = true;
      else if (isG(g, 4)) g4 = true;
      else fail("G" + fmtG(g) + " is not modelled by the simulator");
    }
    if (g43) {
      const int h = w.has('H') ? wholeWord(w, 'H', 0, 9999) : tool_in_spindle_;
      tool_length_ = m_.toolLength(h);
    }
    if (w.has('F')) {
      feed_ = w.take('F');
      if (feed_ < 0) fail("F must not be negative");
    }
    if (w.has('T')) tool_selected_ = wholeWord(w, 'T', 0, 9999);
    bool spindle_word = false, end = false;
    if (w.has('S')) {
      spindle_rpm_ = w.take('S');
      if (spindle_rpm_ < 0) fail("S must not be negative");
    }
    for (double m : w.m) {
      const int mi = static_cast<int>(std::lround(m));
      if (std::fabs(m - mi) > 1e-9) fail("M" + formatG(m) + " is not modelled by the simulator");
      if (mi == 6) {
        m_.toolChange(tool_selected_);
        tool_in_spindle_ = tool_selected_;
      } else if (mi == 3 || mi == 4) {
        spindle_dir_ = mi == 3 ? 1 : -1;
        spindle_word = true;
        m_.spindle(spindle_dir_ * spindle_rpm_);
      } else if (mi == 5) {
        spindle_dir_ = 0;
        spindle_word = true;
        m_.spindle(0);
      } else if (mi == 8) m_.coolant(true);
      else if (mi == 9) m_.coolant(false);
      else if (mi == 2 || mi == 30) end = true;  // after the rest of the line
      else if (mi == 19) {
      }  // spindle orientation: the probe's angular position is fixed anyway
      else fail("M" + std::to_string(mi) + " is not modelled by the simulator");
    }
    // A new S while the spindle turns takes effect at once.
    if (w.has('S') && !spindle_word && spindle_dir_ != 0) m_.spindle(spindle_dir_ * spindle_rpm_);
    const char ax[] = {'X', 'Y', 'Z', 'B', 'C'};
    if (g10) {
      if (!w.has('L') || !w.has('P') || wholeWord(w, 'L', 0, 99) != 2)
        fail("only G10 L2 Pn (set a work offset) is modelled");
      int p = wholeWord(w, 'P', 0, 6);
      if (p == 0) {
        if (in_.dialect_ == ProgramDialect::FanucMacroB)
          fail("G10 L2 P0 is the external offset on a Fanuc control; it is not modelled");
        p = wcs_;
      }
      for (int a = 0; a < 5; ++a)
        if (w.has(ax[a])) offsets_[p][a] = w.take(ax[a]);
      finishWords(w);
      return end;
    }
    if (g4) {
      // LinuxCNC: G4 P seconds, then the line's motion; Fanuc: G4 X seconds (X is the time).
      const char key = in_.dialect_ == ProgramDialect::LinuxCnc ? 'P' : 'X';
      if (!w.has(key)) fail(std::string("G4 needs ") + key + " (seconds)");
      const double t = w.take(key);
      if (t < 0) fail("G4 with a negative time");
      m_.dwell(t);
    }
    if (motion) motion_ = *motion;
    bool axes = false;
    for (char a : ax) axes = axes || (w.has(a) && !w.used.count(a));
    line_ends_ = end;
    if (axes) move(w, g53, g31);
    else if (g31 || g53) fail("G31/G53 without an axis word");
    finishWords(w);
    return end;
  }

  // Every word on a line must have done something: one that did not is refused, so a
  // program the simulator misreads never runs silently.
  void finishWords(const Words& w) {
    for (const auto& [k, v] : w.v)
      if (!w.used.count(k))
        fail("word '" + std::string(1, k) + formatG(v) + "' has no effect on this line (not modelled)");
  }

  void move(Words& w, bool g53, bool g31) {
    MachinePosition to = target(w, g53);
    if (g31) {
      requireFeed();
      probed(m_.probe(to, feed_, ProbeMode::SkipToTarget), ProbeMode::SkipToTarget);
      return;
    }
    if (isG(motion_, 0)) m_.rapid(to);
    else if (isG(motion_, 1)) {
      requireFeed();
      m_.feed(to, feed_);
    } else if (isG(motion_, 2) || isG(motion_, 3)) {
      requireFeed();
      arc(w, to, isG(motion_, 2));
    } else if (isG(motion_, 38.2) || isG(motion_, 38.3)) {
      requireFeed();
      const auto mode = isG(motion_, 38.2) ? ProbeMode::ErrorWithoutContact : ProbeMode::FlagContact;
      probed(m_.probe(to, feed_, mode), mode);
      return;
    } else {
      fail("axis words with G80 active (no motion mode)");
    }
    pos_ = to;
  }

  void requireFeed() {
    if (!(feed_ > 0)) fail("a feed move without a feed rate F");
  }

  // A probe move's outcome. With a ProbeBranching, the rest of the program is first offered
  // with another outcome, from a copy of this run's state (unless this outcome already stops
  // the program: then there is nothing to protect).
  void probed(const ProbeOutcome& r, ProbeMode mode) {
    if (branching_ && !(mode == ProbeMode::ErrorWithoutContact && !r.contact)) {
      branching_->atProbe(r, [this, mode](const ProbeOutcome& other) {
        Execution branch = *this;
        branch.branching_ = nullptr;  // a branch does not branch again
        return branch.continueAfterProbe(other, mode);
      });
    }
    applyProbe(r, mode);
  }
  void applyProbe(const ProbeOutcome& r, ProbeMode mode) {
    if (mode == ProbeMode::ErrorWithoutContact && !r.contact)
      stop(in_.file_, line_, "G38.2 probe move finished without contact");
    if (mode != ProbeMode::SkipToTarget) params_[5070] = r.contact ? 1 : 0;
    setProbeResult(r);
  }
  // A branch: this probe line finishes with `other`, then the program runs on from the next
  // line (nothing on a probe line acts after its move but an M2/M30 on it).
  InterpreterResult continueAfterProbe(const ProbeOutcome& other, ProbeMode mode) {
    applyProbe(other, mode);
    if (line_ends_) return InterpreterResult{blocks_, true};
    return runFrom(pc_ + 1);
  }

  static std::string fmtG(double g) {
    char b[16];
    std::snprintf(b, sizeof b, "%g", g);
    return b;
  }

  std::array<double, 5> activeOffset() const {
    auto o = offsets_[static_cast<std::size_t>(wcs_)];
    o[2] += tool_length_;
    return o;
  }

  MachinePosition target(Words& w, bool machine_coords) {
    MachinePosition t = pos_;
    const auto off = machine_coords ? std::array<double, 5>{} : activeOffset();
    if (machine_coords && !absolute_) fail("G53 with G91 is not allowed");
    double* dst[] = {&t.xyz_mm.x(), &t.xyz_mm.y(), &t.xyz_mm.z(), &t.b_deg, &t.c_deg};
    const double cur[] = {pos_.xyz_mm.x(), pos_.xyz_mm.y(), pos_.xyz_mm.z(), pos_.b_deg, pos_.c_deg};
    const char ax[] = {'X', 'Y', 'Z', 'B', 'C'};
    for (int a = 0; a < 5; ++a) {
      if (!w.has(ax[a])) continue;
      const double v = w.take(ax[a]);
      *dst[a] = absolute_ ? v + off[static_cast<std::size_t>(a)] : cur[a] + v;
      if (!std::isfinite(*dst[a]))
        fail(std::string("the ") + ax[a] + " target (" + formatG(v) + " plus the offset or the current position) is not a "
             "finite number (overflow); the controller stops here");
    }
    return t;
  }

  // After a probe move both dialects report the latched position in program coordinates.
  void setProbeResult(const ProbeOutcome& r) {
    const auto off = activeOffset();
    params_[5061] = r.stop.xyz_mm.x() - off[0];
    params_[5062] = r.stop.xyz_mm.y() - off[1];
    params_[5063] = r.stop.xyz_mm.z() - off[2];
    params_[5064] = r.stop.b_deg - off[3];
    params_[5065] = r.stop.c_deg - off[4];
    pos_ = r.stop;
  }

  // G2/G3 in the XY plane as chords within 0.1 um of the arc.
  void arc(Words& w, const MachinePosition& to, bool clockwise) {
    const Eigen::Vector2d a = pos_.xyz_mm.head<2>(), b = to.xyz_mm.head<2>();
    Eigen::Vector2d centre;
    if (w.has('R')) {
      const double r = w.take('R'), d = (b - a).norm();
      if (std::fabs(r) > 1e5) fail("arc radius R" + formatG(r) + " mm is not plausible");
      if (d < 1e-9 || std::fabs(r) < d / 2 - 1e-9) fail("arc radius R is too small for the end point");
      const double h = std::sqrt(std::max(0.0, r * r - d * d / 4));
      const Eigen::Vector2d mid = (a + b) / 2, perp = Eigen::Vector2d(-(b - a).y(), (b - a).x()) / d;
      // R > 0: the short arc; the centre lies to the right of a->b for G2.
      const double side = (clockwise ? -1.0 : 1.0) * (r > 0 ? 1.0 : -1.0);
      centre = mid + side * h * perp;
    } else {
      if (!w.has('I') && !w.has('J')) fail("G2/G3 needs I/J (centre) or R");
      centre = a + Eigen::Vector2d(w.has('I') ? w.take('I') : 0.0, w.has('J') ? w.take('J') : 0.0);
    }
    const double ra = (a - centre).norm(), rb = (b - centre).norm();
    if (ra < 1e-9) fail("arc with zero radius");
    if (std::fabs(ra - rb) > 0.002) fail("arc end point is not on the arc (radius differs by " + std::to_string(std::fabs(ra - rb)) + " mm)");
    double t0 = std::atan2(a.y() - centre.y(), a.x() - centre.x());
    double t1 = std::atan2(b.y() - centre.y(), b.x() - centre.x());
    double sweep = t1 - t0;
    if (clockwise) {
      if (sweep >= -1e-12) sweep -= 2 * kPi;
    } else if (sweep <= 1e-12) sweep += 2 * kPi;
    if (ra > 1e5) fail("arc radius " + formatG(ra) + " mm is not plausible");
    const double tol = 1e-4;
    const double max_step = 2 * std::acos(std::max(-1.0, 1 - tol / ra));
    const double chords = std::ceil(std::fabs(sweep) / max_step);
    if (!(chords <= 1e6)) fail("arc needs more than 1e6 chords within 0.1 um; not modelled");
    const int n = std::max(1, static_cast<int>(chords));
    for (int k = 1; k <= n; ++k) {
      const double s = static_cast<double>(k) / n;
      MachinePosition p = to;
      if (k < n) {
        const double t = t0 + sweep * s;
        p.xyz_mm.x() = centre.x() + ra * std::cos(t);
        p.xyz_mm.y() = centre.y() + ra * std::sin(t);
        p.xyz_mm.z() = pos_.xyz_mm.z() + (to.xyz_mm.z() - pos_.xyz_mm.z()) * s;
      }
      m_.feed(p, feed_);
    }
  }
};

InterpreterResult Interpreter::run(MachineInterface& machine, long max_blocks, ProbeBranching* branching) {
  Execution e(*this, machine, branching);
  try {
    const auto r = e.run(max_blocks);
    e.publishParameters();
    return r;
  } catch (...) {
    e.publishParameters();
    throw;
  }
}

}  // namespace probeloop::gcode
