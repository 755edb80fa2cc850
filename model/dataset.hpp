// A campaign as the model sees it: the machine's logged inputs (inputs.csv from probeloop
// simulate or a controller logger: time_s then one column per input, on a uniform grid) and
// the evaluated errors (errors.csv from probeloop evaluate: time_s, cycle, one column per
// error channel, and U_<channel> for each).
//
// Contract (every refusal is an InputError with file:line and what was expected):
// - inputs: strictly increasing times on a uniform step (a gap longer than 1.5 steps is
//   refused, naming the two lines), every field finite (NaN, empty or text: the line and
//   the column), at least 2 rows;
// - errors: strictly increasing times, finite values, U >= 0;
// - the two time bases must be the same clock: every error time lies within the inputs'
//   span (otherwise "misaligned time bases" with both spans);
// - inputsAt: an input column sampled at the error times by linear interpolation.
#pragma once
#include <string>
#include <vector>

namespace probeloop::model {

struct InputSeries {
  std::string file;
  std::vector<double> t_s;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;  // [input][sample]
  double step_s = 0;
  int column(const std::string& name) const;  // -1 if absent
};

struct ErrorSeries {
  std::string file;
  std::vector<double> t_s;
  std::vector<std::string> channels;           // e.g. EY0C_um
  std::vector<std::vector<double>> values;     // [channel][sample]
  std::vector<std::vector<double>> U;          // [channel][sample], k = 2; all 0 when absent
  int channel(const std::string& name) const;  // -1 if absent; also accepts "EY0C" for "EY0C_um"
  int size() const { return static_cast<int>(t_s.size()); }
};

struct Campaign {
  InputSeries inputs;
  ErrorSeries errors;
  // Interpolates a grid series (one value per inputs.t_s) at the error times.
  std::vector<double> atErrorTimes(const std::vector<double>& grid_values) const;
};

InputSeries loadInputs(const std::string& path);
ErrorSeries loadErrors(const std::string& path);
Campaign loadCampaign(const std::string& inputs_path, const std::string& errors_path);

// The unit of a channel from its name's suffix ("EY0C_um" -> "um").
std::string channelUnit(const std::string& channel);

}  // namespace probeloop::model
