// Test support shared by the report pages' unit tests: a scratch folder with a stand-in Vega
// bundle (the tests check the page the C++ writes; that Vega really draws it is the job of
// tests/integration/html_render.py and the *_report_check.py scripts, in headless Chromium), and
// the page's parts read back: a needle's count, the Vega spec of plot k, a dataset of a spec.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace probeloop::report::testing {

// A fixture's scratch folder, probeloop-<name>-<pid> under the temp directory, with vega.min.js.
class PageTest : public ::testing::Test {
 protected:
  explicit PageTest(std::string name) : name_(std::move(name)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("probeloop-" + name_ + "-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    vega_ = (dir_ / "vega.min.js").string();
    std::ofstream(vega_) << "/* stand-in vega */ window.vega = {};\n";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
  std::string vega_;

 private:
  std::string name_;
};

inline std::size_t count(const std::string& hay, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + needle.size())) ++n;
  return n;
}

// The Vega spec of plot k (1-based), parsed back from its <script type="application/json">; null
// when the page has no plot k.
inline nlohmann::json spec(const std::string& html, int k) {
  const std::string open = "<script type=\"application/json\" id=\"plot-" + std::to_string(k) + "-spec\">";
  const std::size_t a = html.find(open);
  if (a == std::string::npos) return nullptr;
  const std::size_t b = html.find("</script>", a);
  return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

inline nlohmann::json dataset(const nlohmann::json& s, const std::string& name) {
  for (const auto& d : s["data"])
    if (d["name"] == name) return d;
  return nullptr;
}

}  // namespace probeloop::report::testing
