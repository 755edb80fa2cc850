// What a run writes (interpreter_detail.hpp): Fanuc DPRNT, LinuxCNC active comments and the
// parameters substituted in LOG text.
#include "gcode/interpreter_detail.hpp"

#include <cstdio>

namespace probeloop::gcode {

std::string Execution::dprnt(const std::string& body) {
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

void Execution::activeComment(const std::string& body) {
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

std::string Execution::substitute(const std::string& text) {
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

std::string Execution::fmtLf(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%f", v);
  return b;
}

}  // namespace probeloop::gcode
