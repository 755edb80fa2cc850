// Control flow of a run (interpreter_detail.hpp): o-words, Fanuc labels, WHILE/DO/END, GOTO,
// IF, resolved once before the run and taken during it.
#include "gcode/interpreter_detail.hpp"

namespace probeloop::gcode {

std::optional<Execution::OWord> Execution::oword(const std::string& code) const {
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

void Execution::buildJumps() {
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

void Execution::controlLinux(const OWord& o, const std::string& code, std::size_t& next) {
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

bool Execution::condition(Cursor& c) {
  if (c.peek() != '[') fail("expected a [condition]");
  const double v = bracket(c);
  if (!c.end()) fail("unexpected '" + c.s.substr(c.i) + "' after the condition");
  return v != 0;
}

bool Execution::controlFanuc(const std::string& rest, std::size_t& next) {
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

std::size_t Execution::label(int n) {
  const auto it = control_->labels.find(n);
  if (it == control_->labels.end()) fail("GOTO " + std::to_string(n) + ": no block N" + std::to_string(n));
  return it->second;
}

}  // namespace probeloop::gcode
