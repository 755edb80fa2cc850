// The error-model file: what `probeloop model add` writes loads back as the same model, with
// any path or name; bad files are refused with their line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "parts/error_model_file.hpp"

using namespace probeloop;

namespace {
std::string tempFile(const std::string& name, const std::string& text) {
  const auto p = (std::filesystem::temp_directory_path() / ("probeloop_em_" + name)).string();
  std::ofstream(p) << text;
  return p;
}
}  // namespace

TEST(ErrorModelFile, WhatIsWrittenLoadsBackTheSame) {
  model::ErrorModel m;
  m.inputs_path = "run #1/in: \"quoted\" \\ inputs.csv";
  m.errors_path = "*eval/errors.csv";
  m.training_fraction = 0.55;
  model::Effect lag = model::makeEffect(model::EffectKind::Lag, "c_rpm");
  lag.tau_s = 7529.172352784451;
  lag.just_added = true;
  model::Effect fixed = model::makeEffect(model::EffectKind::Transient, "tool_changes");
  fixed.tau_s = 0.4;
  fixed.tau_fixed = true;
  model::Effect exp = model::makeEffect(model::EffectKind::Expansion, "T_table_C");
  exp.alpha_um_per_m_K = 11.5;
  exp.length_mm = 90;
  model::Effect scale = model::makeEffect(model::EffectKind::Lag, "spindle_rpm");
  scale.lever = "travel_mm";
  m.channels = {{"EY0C_um", {lag, model::makeEffect(model::EffectKind::Drift)}}, {"EZ0T_um", {fixed, exp}}, {"EX0C_um", {scale}}};
  const auto path = tempFile("roundtrip.yaml", "");
  parts::saveErrorModel(m, path);
  const auto back = parts::loadErrorModel(path);
  EXPECT_EQ(back.inputs_path, m.inputs_path);
  EXPECT_EQ(back.errors_path, m.errors_path);
  EXPECT_EQ(back.training_fraction, 0.55);
  ASSERT_EQ(back.channels.size(), 3u);
  for (std::size_t c = 0; c < 3; ++c) {
    EXPECT_EQ(back.channels[c].channel, m.channels[c].channel);
    ASSERT_EQ(back.channels[c].effects.size(), m.channels[c].effects.size());
    for (std::size_t k = 0; k < m.channels[c].effects.size(); ++k) {
      const auto &a = m.channels[c].effects[k], &b = back.channels[c].effects[k];
      EXPECT_EQ(b.id(), a.id());
      EXPECT_EQ(b.tau_s.has_value(), a.tau_s.has_value());
      if (a.tau_s) {
        EXPECT_EQ(*b.tau_s, *a.tau_s);  // shortest round-trip decimal: exact
      }
      EXPECT_EQ(b.tau_fixed, a.tau_fixed);
      EXPECT_EQ(b.just_added, a.just_added);
      EXPECT_EQ(b.alpha_um_per_m_K, a.alpha_um_per_m_K);
      EXPECT_EQ(b.length_mm, a.length_mm);
      EXPECT_EQ(b.lever, a.lever);
    }
  }
  EXPECT_EQ(parts::errorModelYaml(back), parts::errorModelYaml(m));
}

TEST(ErrorModelFile, RefusesBadFilesWithTheirLine) {
  auto msg = [](const std::string& name, const std::string& text) {
    try {
      parts::loadErrorModel(tempFile(name, text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(msg("k.yaml", "kind: gum_model\nchannels: {E: []}\n").find("expected 'error_model'"), std::string::npos);
  EXPECT_NE(msg("e.yaml", "kind: error_model\nchannels:\n  E:\n    - {effect: lag, input: T, tau: -1 s}\n").find(":4:"),
            std::string::npos);
  EXPECT_NE(msg("f.yaml", "kind: error_model\nchannels:\n  E: [{effect: lag, input: T, tau_fixed: true}]\n")
                .find("a fixed time constant needs tau"),
            std::string::npos);
  EXPECT_NE(msg("x.yaml", "kind: error_model\nchannels:\n  E: [{effect: expansion, input: T, alpha_um_per_m_K: 0, length: 9 mm}]\n")
                .find("must be > 0"),
            std::string::npos);
  EXPECT_NE(msg("t.yaml", "kind: error_model\ntraining_fraction: 1.5\nchannels: {E: []}\n").find("(0, 1]"), std::string::npos);
  EXPECT_NE(msg("u.yaml", "kind: error_model\nchannels: {E: []}\nextra: 1\n").find("extra"), std::string::npos);
  EXPECT_NE(msg("l.yaml", "kind: error_model\nchannels:\n  E: [{effect: transient, input: tool_changes, lever: travel_mm}]\n")
                .find("only a static or lag effect acts over a lever"),
            std::string::npos);
}

// `model add` edits the user's text: comments and layout stay, the edit means exactly the
// updated model, and a layout it does not edit in place is left to the canonical form.
TEST(ErrorModelFile, PatchKeepsCommentsAndMeansTheUpdatedModel) {
  const std::string text =
      "# my model\n"
      "kind: error_model   # always\n"
      "channels:\n"
      "  EX0C_um: [{effect: static, input: T_table_C, just_added: true}]  # first [guess]\n"
      "  EY0C_um:\n"
      "    - {effect: static, input: T_caxis_C}\n"
      "\n"
      "  # the radius: offset only\n"
      "  ER0T_um: []\n";
  auto m = parts::errorModelFromText(text, "m.yaml");
  m.channels[0].effects[0].just_added = false;
  model::Effect lag = model::makeEffect(model::EffectKind::Lag, "T_env_C");
  lag.just_added = true;
  m.channels[0].effects.push_back(lag);
  m.channels[1].effects.push_back(lag);
  m.channels[2].effects.push_back(lag);
  m.channels.push_back({"EZ0T_um", {lag}});
  const auto out = parts::patchErrorModelText(text, m);
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(*out,
            "# my model\n"
            "kind: error_model   # always\n"
            "channels:\n"
            "  EX0C_um: [{effect: static, input: T_table_C}, {effect: lag, input: \"T_env_C\", just_added: true}]  # first [guess]\n"
            "  EY0C_um:\n"
            "    - {effect: static, input: T_caxis_C}\n"
            "    - {effect: lag, input: \"T_env_C\", just_added: true}\n"
            "\n"
            "  # the radius: offset only\n"
            "  ER0T_um: [{effect: lag, input: \"T_env_C\", just_added: true}]\n"
            "  \"EZ0T_um\":\n"
            "    - {effect: lag, input: \"T_env_C\", just_added: true}\n");
  EXPECT_EQ(parts::errorModelYaml(parts::errorModelFromText(*out, "m.yaml")), parts::errorModelYaml(m));
  // A flow-style channels map is not edited in place: the caller writes the canonical form.
  const std::string flow = "kind: error_model\nchannels: {EX0C_um: []}\n";
  auto f = parts::errorModelFromText(flow, "f.yaml");
  f.channels[0].effects.push_back(lag);
  EXPECT_FALSE(parts::patchErrorModelText(flow, f).has_value());
}

// Seed 003's force-induced error as written in a model file (docs/formats.md#error-model).
TEST(ErrorModelFile, ReadsAndWritesTheForceEffect) {
  const std::string text =
      "kind: error_model\nchannels:\n  EY_um:\n    - {effect: force, input: F_y_N}\n";
  const auto m = parts::errorModelFromText(text, "m.yaml");
  ASSERT_EQ(m.channels.size(), 1u);
  ASSERT_EQ(m.channels[0].effects.size(), 1u);
  EXPECT_EQ(m.channels[0].effects[0].kind, model::EffectKind::Force);
  EXPECT_EQ(m.channels[0].effects[0].id(), "force(F_y_N)");
  EXPECT_NE(parts::errorModelYaml(m).find("- {effect: force, input: \"F_y_N\"}"), std::string::npos) << parts::errorModelYaml(m);
  EXPECT_THROW(parts::errorModelFromText("kind: error_model\nchannels:\n  EY_um:\n    - {effect: force, input: F_y_N, lever: x_mm}\n", "m.yaml"),
               InputError);
}
