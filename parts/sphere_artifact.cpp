#include "parts/sphere_artifact.hpp"

#include <cmath>

#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

SphereArtifact loadSphereArtifact(const std::string& path) {
  YamlMap root(loadYamlFile(path), path, "");
  SphereArtifact a;
  a.file = path;
  root.choice("kind", {"sphere_artifact"});

  YamlMap s = root.map("sphere");
  a.sphere_diameter_mm = s.quantity("diameter", Dimension::Length);
  a.sphere_form_error_um = s.quantityOr("form_error", Dimension::Micrometre, 0.0);
  a.stem_diameter_mm = s.quantity("stem_diameter", Dimension::Length);
  a.stem_length_mm = s.quantity("stem_length", Dimension::Length);
  if (!(a.sphere_diameter_mm > 0)) s.fail("diameter", "must be positive");
  if (!(a.stem_diameter_mm > 0 && a.stem_diameter_mm < a.sphere_diameter_mm))
    s.fail("stem_diameter", "must be positive and smaller than the sphere diameter");
  if (!(a.stem_length_mm >= 0)) s.fail("stem_length", "must not be negative");
  s.finish();

  YamlMap p = root.map("placement");
  a.radius_from_axis_mm = p.quantity("radius_from_c_axis", Dimension::Length);
  a.angle_at_c0_deg = p.quantity("angle_at_c0", Dimension::Angle);
  if (!(a.radius_from_axis_mm > 0)) p.fail("radius_from_c_axis", "must be positive (d/2 > 0)");
  p.finish();

  a.c_positions_deg = root.quantityList("c_positions", Dimension::Angle);
  if (a.c_positions_deg.size() < 3)
    root.fail("c_positions", "at least 3 C positions are needed to separate the location errors");

  if (root.has("tilted_positions"))
    for (auto& t : root.mapList("tilted_positions")) {
      SphereArtifact::TiltedPosition tp;
      tp.line = t.line();
      const bool b = t.has("B"), has_a = t.has("A");
      if (b == has_a) t.fail(b ? "A" : "B", "a tilted position names one tilting axis, B or A (and C)");
      tp.tilt_deg = t.quantity(b ? "B" : "A", Dimension::Angle);
      tp.c_deg = t.quantity("C", Dimension::Angle);
      if (tp.tilt_deg == 0) t.fail(b ? "B" : "A", "0 is not tilted: list it under c_positions");
      const char letter = b ? 'B' : 'A';
      if (a.tilt_axis && a.tilt_axis != letter)
        t.fail(b ? "B" : "A", std::string("every tilted position tilts the same axis (") + a.tilt_axis + " above)");
      a.tilt_axis = letter;
      t.finish();
      a.tilted_positions.push_back(tp);
    }

  YamlMap pr = root.map("probing");
  a.equator_points = pr.integer("equator_points");
  a.top_point = pr.boolean("top_point");
  a.probing_feed_mm_per_min = pr.quantity("feed", Dimension::Feed);
  a.positioning_feed_mm_per_min = pr.quantity("positioning_feed", Dimension::Feed);
  a.approach_mm = pr.quantity("approach", Dimension::Length);
  a.overtravel_mm = pr.quantity("overtravel", Dimension::Length);
  a.clearance_mm = pr.quantity("clearance_above_sphere", Dimension::Length);
  if (a.equator_points < 3) pr.fail("equator_points", "need at least 3 equator points");
  if (a.pointsPerPosition() < 4)
    pr.fail("equator_points", "a sphere needs >= 4 points (equator points + top point)");
  if (!a.top_point)
    pr.fail("top_point",
            "equator points alone are coplanar; the top point is needed to fix the centre height");
  if (!(a.probing_feed_mm_per_min > 0)) pr.fail("feed", "must be positive");
  if (!(a.positioning_feed_mm_per_min > 0)) pr.fail("positioning_feed", "must be positive");
  if (!(a.approach_mm > 0)) pr.fail("approach", "must be positive");
  if (!(a.overtravel_mm > 0)) pr.fail("overtravel", "must be positive");
  if (!(a.clearance_mm > a.approach_mm))
    pr.fail("clearance_above_sphere", "must exceed the approach distance");
  pr.finish();

  YamlMap c = root.map("cycles");
  const bool has_count = c.has("count"), has_duration = c.has("duration");
  if (has_count == has_duration) c.fail("count", "give exactly one of 'count' or 'duration'");
  if (has_count) {
    a.cycle_count = c.integer("count");
    if (a.cycle_count < 1) c.fail("count", "must be >= 1");
  } else {
    a.duration_s = c.quantity("duration", Dimension::Duration);
    if (!(a.duration_s > 0)) c.fail("duration", "must be positive");
  }
  a.gap_s = c.quantity("gap", Dimension::Duration);
  if (a.gap_s < 0) c.fail("gap", "must not be negative");
  a.tool_change_each_cycle = c.boolean("tool_change_each_cycle");
  a.live_interval = c.booleanOr("live_interval", false);
  c.finish();

  if (auto u = root.mapIfPresent("uncertainty")) {
    a.radius_from_axis_u_mm = u->quantityOr("radius_from_c_axis_u", Dimension::Length, NAN);
    a.alpha_um_per_m_K = u->numberOr("alpha_um_per_m_K", NAN);
    a.temperature_change_half_width_K = u->quantityOr("temperature_change_half_width", Dimension::Temperature, NAN);
    if (u->has("radius_from_c_axis_u") && !(a.radius_from_axis_u_mm >= 0))
      u->fail("radius_from_c_axis_u", "a standard uncertainty must be >= 0");
    if (u->has("alpha_um_per_m_K") && !(a.alpha_um_per_m_K >= 0 && a.alpha_um_per_m_K < 100))
      u->fail("alpha_um_per_m_K", "expected an expansion coefficient in um/(m K), e.g. 11.5 for steel");
    if (u->has("temperature_change_half_width") && !(a.temperature_change_half_width_K >= 0))
      u->fail("temperature_change_half_width", "a half-width must be >= 0");
    u->finish();
  }
  root.finish();
  return a;
}

}  // namespace probeloop::parts
