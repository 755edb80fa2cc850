// The interpreter (interpreter.hpp): the program's text read into lines, the run and the
// dispatch of each line; what a run does with a line is in the files interpreter_detail.hpp
// names.
#include "gcode/interpreter.hpp"

#include <cctype>

#include "core/error.hpp"
#include "gcode/interpreter_detail.hpp"

namespace probeloop::gcode {

namespace {

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

InterpreterResult Execution::runFrom(std::size_t start) {
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

bool Execution::executeLine(const Interpreter::Line& line, std::size_t& next) {
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
