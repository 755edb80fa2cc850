// An error model: the effects of each error channel (docs/architecture.md#how-to-add-an-effect), as written in a model
// file (YAML, kind: error_model; docs/formats.md#error-model; loaded by parts/).
//
// Every channel has an offset implicitly: the errors are relative to a reference cycle, and
// the offset is what the effects leave at t = 0. Only channels listed are modelled.
#pragma once
#include <string>
#include <vector>

#include "model/effects.hpp"

namespace probeloop::model {

struct ChannelModel {
  std::string channel;          // as in errors.csv, e.g. EY0C_um
  std::vector<Effect> effects;  // without the implicit offset
};

struct ErrorModel {
  std::string file;
  std::string inputs_path, errors_path;  // data the file names, as written (relative to its folder); may be empty
  double training_fraction = 0.6;        // seed 004 trains on the first 60 %, validates on the rest
  std::vector<ChannelModel> channels;

  const ChannelModel* channel(const std::string& name) const;
  // The model without the effects marked just_added ("before" the last `model add`);
  // false when nothing is marked.
  bool before(ErrorModel& out) const;
};

}  // namespace probeloop::model
