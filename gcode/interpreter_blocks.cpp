// An ordinary block of a run (interpreter_detail.hpp): its words read and checked, the modal
// state it sets, every word made to act.
#include "gcode/interpreter_detail.hpp"

#include <cstdio>

namespace probeloop::gcode {

bool Execution::block(const std::string& code) {
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
    static const std::string lengths = "XYZABCIJR";
    if (in_.dialect_ == ProgramDialect::FanucMacroB && lengths.find(letter) != std::string::npos && v != 0 &&
        code.substr(value_at, c.i - value_at).find_first_of(".#[") == std::string::npos)
      fail(std::string("'") + letter + code.substr(value_at, c.i - value_at) +
           "' has no decimal point: a Fanuc control reads it in least input increments (um), "
           "not mm; write it with a point");
    if (letter == 'G') w.g.push_back(std::round(v * 10) / 10);
    else if (letter == 'M') w.m.push_back(v);
    else if (letter == 'N') continue;
    else {
      static const std::string allowed = "XYZABCFSTHPLIJR";
      // E: the analog input of LinuxCNC's M66 E<n> L0 (execute refuses it anywhere else).
      const bool analog_input = letter == 'E' && in_.dialect_ == ProgramDialect::LinuxCnc;
      if (allowed.find(letter) == std::string::npos && !analog_input)
        fail("word '" + std::string(1, letter) + "' is not modelled by the simulator");
      if (w.v.count(letter)) fail("word '" + std::string(1, letter) + "' appears twice");
      w.v[letter] = v;
    }
  }
  return execute(w);
}

int Execution::wholeWord(Words& w, char k, int lo, int hi) {
  const double v = w.take(k);
  if (!(v >= lo && v <= hi) || std::fabs(v - std::round(v)) > 1e-9)
    fail(std::string(1, k) + formatG(v) + ": expected a whole number " + std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<int>(std::lround(v));
}

std::string Execution::formatG(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

bool Execution::execute(Words& w) {
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
  bool spindle_word = false, end = false, m66 = false;
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
    else if (mi == 66 && in_.dialect_ == ProgramDialect::LinuxCnc) m66 = true;
    else if (mi == 19) {
    }  // spindle orientation: the probe's angular position is fixed anyway
    else fail("M" + std::to_string(mi) + " is not modelled by the simulator");
  }
  if (m66) {
    analogRead(w);
    return end;
  }
  // A new S while the spindle turns takes effect at once.
  if (w.has('S') && !spindle_word && spindle_dir_ != 0) m_.spindle(spindle_dir_ * spindle_rpm_);
  const char ax[] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
  if (g10) {
    if (!w.has('L') || !w.has('P') || wholeWord(w, 'L', 0, 99) != 2)
      fail("only G10 L2 Pn (set a work offset) is modelled");
    int p = wholeWord(w, 'P', 0, 6);
    if (p == 0) {
      if (in_.dialect_ == ProgramDialect::FanucMacroB)
        fail("G10 L2 P0 is the external offset on a Fanuc control; it is not modelled");
      p = wcs_;
    }
    for (int a = 0; a < 6; ++a)
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

void Execution::analogRead(Words& w) {
  // The one form the planner emits (the sphere cycle's live interval): an immediate read of an
  // analog input. The other forms wait on an input or read a digital one; a run that took
  // them for this would time and branch differently from the controller, so they are refused.
  const std::string form = "only M66 E<n> L0 (read analog input n at once into #5399) is modelled";
  if (w.g.size() + w.m.size() != 1)
    fail("M66 E<n> L0 must stand on a line of its own here (no G or other M code with it); " + form);
  if (w.has('P')) fail("M66 P (a digital input) is not modelled; " + form);
  if (!w.has('E')) fail("M66 without E<n> (the analog input); " + form);
  if (!w.has('L')) fail("M66 without L0 (the wait mode); " + form);
  const int n = wholeWord(w, 'E', 0, 63);  // LinuxCNC has at most 64 analog inputs (num_aio)
  const int mode = wholeWord(w, 'L', 0, 4);
  if (mode != 0) fail("M66 L" + std::to_string(mode) + " waits on the input; " + form);
  finishWords(w);  // an axis or any other word on the line
  const double v = m_.analogInput(n);
  if (!std::isfinite(v)) fail("analog input " + std::to_string(n) + " reads a value that is not a finite number");
  params_[5399] = v;
}

void Execution::finishWords(const Words& w) {
  for (const auto& [k, v] : w.v)
    if (!w.used.count(k))
      fail("word '" + std::string(1, k) + formatG(v) + "' has no effect on this line (not modelled)");
}

std::string Execution::fmtG(double g) {
  char b[16];
  std::snprintf(b, sizeof b, "%g", g);
  return b;
}

}  // namespace probeloop::gcode
