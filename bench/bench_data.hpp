// Benchmark point files: one deterministic binary file per data set, read by the C++
// benchmark, the PCL harness and bench/scipy_fit.py alike, so every fitter sees the same
// numbers.
//
// Layout (little endian):
//   256-byte header
//     0   char[8]   magic "PLBENCH1"
//     8   uint32    kind (see DataKind)
//     12  uint32    1 if unit normals follow the points, else 0
//     16  uint64    n, number of points
//     24  double[8] truth: position xyz, direction xyz, radius, 0
//     88  double[8] start: the same fields; the start every iterative fitter gets
//     152 zero padding up to 256
//   n x 3 float64 xyz (mm)
//   n x 3 float64 unit normals (only if the flag is set): the exact outward normal of the
//     generating surface at the noise-free point (PCL's cylinder model wants normals)
#pragma once
#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace probeloop::bench {

enum class DataKind : std::uint32_t {
  Plane = 1,      // LS plane: 200 x 200 mm, tilted, 1 um noise
  Sphere = 2,     // LS sphere: r = 25 mm hemisphere, 1 um noise
  Cylinder = 3,   // LS cylinder: full 360 deg, r = 20 mm, 100 mm long, tilted, 1 um noise
  Roundness = 4,  // MZ circle2d: r = 25 mm, 3- and 5-lobed form + 0.5 um noise
  Flatness = 5,   // MZ plane: 200 x 200 mm, tilted, saddle form + 0.5 um noise
};

const char* dataKindName(DataKind kind);

struct ElementParams {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double radius = 0.0;
};

struct DataSet {
  DataKind kind = DataKind::Plane;
  ElementParams truth;
  ElementParams start;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;  // empty unless stored
};

// Deterministic: the same (kind, n) always gives the same bytes.
DataSet generate(DataKind kind, std::size_t n);
void writeDataSet(const std::string& path, const DataSet& data);
// Throws std::runtime_error naming the file on any mismatch.
DataSet readDataSet(const std::string& path);

}  // namespace probeloop::bench
