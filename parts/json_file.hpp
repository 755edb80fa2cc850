// A JSON input (an evaluation.json, a separation.json) read whole: InputError naming the file
// when it is not JSON, with what the file looks like instead (core/input_file.hpp).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.hpp"
#include "core/input_file.hpp"

namespace probeloop::parts {

inline nlohmann::json readJsonFile(const std::string& path) {
  const std::string text = readFile(path, kJsonInput);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const std::string kind = describeContent(text);
    throw InputError(path, 0, std::string("not valid JSON (") + e.what() + ")" +
                                  (kind.empty() || kind.find("JSON") != std::string::npos ? "" : "; the file looks like " + kind));
  }
}

}  // namespace probeloop::parts
