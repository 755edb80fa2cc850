// The stock as it is being cut by flat end mills, in the workpiece frame.
//
// Two representations of the same material:
// - a height field (Z-map, cells of `cell_mm`) for what a move removes (volume, where) and
//   for collision checks: coarse, fast;
// - the exact surface: the box minus the union of the swept volumes of every cut (a flat
//   end mill moving on a horizontal segment sweeps {xy within r of the segment, z >= bottom};
//   a plunge sweeps a cylinder). A line query returns where the line first enters material,
//   to floating-point precision, so CMM and probe points see micrometre-level cut errors.
//
// Contract: cut() records one swept volume per horizontal or vertical segment; a ramp (XY
// and Z together) is split into pieces of at most 0.1 mm, each at its upper Z (the floor
// of a ramp is then within slope x 0.1 mm). Volumes in mm^3.
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <vector>

namespace probeloop::sim {

struct SweptCut {
  Eigen::Vector3d p0, p1;  // tool-bottom centre at the start and end, workpiece frame
  double radius = 0;
  double time_s = 0;
};

struct Removal {
  double volume_mm3 = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // of the removed material
};

class Stock {
 public:
  Stock() = default;
  Stock(const Eigen::Vector3d& min_mm, const Eigen::Vector3d& max_mm, double cell_mm = 0.25);

  // The height field part: what the move from p0 to p1 removes (undisplaced tool path).
  Removal removeHeightField(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius);
  // The exact part: the swept volume of the real (displaced) tool path.
  void recordCut(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius, double time_s);

  // Highest material under a disk (cells whose centres lie within `radius` of xy) per the
  // height field; -inf if none.
  double topUnder(const Eigen::Vector2d& xy, double radius) const;
  // First s in [0, max_s] where from + s dir enters material (exact surface); nullopt if none.
  std::optional<double> firstMaterial(const Eigen::Vector3d& from, const Eigen::Vector3d& dir, double max_s) const;

  const Eigen::Vector3d& min() const { return min_; }
  const Eigen::Vector3d& max() const { return max_; }

 private:
  Eigen::Vector3d min_ = Eigen::Vector3d::Zero(), max_ = Eigen::Vector3d::Zero();
  double cx_ = 0.25, cy_ = 0.25;
  int nx_ = 0, ny_ = 0;
  int cellX(double x) const;
  int cellY(double y) const;
  std::vector<double> top_;
  std::vector<SweptCut> cuts_;
};

}  // namespace probeloop::sim
