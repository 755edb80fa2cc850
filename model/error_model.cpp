#include "model/error_model.hpp"

namespace probeloop::model {

const ChannelModel* ErrorModel::channel(const std::string& name) const {
  for (const auto& c : channels)
    if (c.channel == name) return &c;
  return nullptr;
}

bool ErrorModel::before(ErrorModel& out) const {
  out = *this;
  bool any = false;
  for (auto& c : out.channels) {
    const auto n = c.effects.size();
    std::erase_if(c.effects, [](const Effect& e) { return e.just_added; });
    any = any || c.effects.size() != n;
  }
  return any;
}

}  // namespace probeloop::model
