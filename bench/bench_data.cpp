#include "bench/bench_data.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <stdexcept>

namespace probeloop::bench {
namespace {

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "points are stored as packed xyz");

constexpr char kMagic[8] = {'P', 'L', 'B', 'E', 'N', 'C', 'H', '1'};
constexpr std::size_t kHeaderBytes = 256;

// splitmix64 + Box-Muller: the same stream on every platform (std::normal_distribution
// is implementation-defined).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double gauss() {
    if (have_spare_) {
      have_spare_ = false;
      return spare_;
    }
    double u1 = 0.0;
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double m = std::sqrt(-2.0 * std::log(u1));
    spare_ = m * std::sin(2.0 * std::numbers::pi * u2);
    have_spare_ = true;
    return m * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::uint64_t state_;
  double spare_ = 0.0;
  bool have_spare_ = false;
};

// Two unit vectors completing `w` to a right-handed orthonormal frame.
void frame(const Eigen::Vector3d& w, Eigen::Vector3d& u, Eigen::Vector3d& v) {
  const Eigen::Vector3d a =
      std::abs(w.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  u = (a - a.dot(w) * w).normalized();
  v = w.cross(u);
}

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (const auto& p : pts) s += p;
  return s / static_cast<double>(pts.size());
}

// Algebraic (Kasa) sphere fit relative to the centroid: |q|^2 = 2 a.q + b.
ElementParams algebraicSphere(const std::vector<Eigen::Vector3d>& pts) {
  const Eigen::Vector3d m = centroid(pts);
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
  Eigen::Vector4d aty = Eigen::Vector4d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d q = p - m;
    const Eigen::Vector4d row(2.0 * q.x(), 2.0 * q.y(), 2.0 * q.z(), 1.0);
    ata.noalias() += row * row.transpose();
    aty += row * q.squaredNorm();
  }
  const Eigen::Vector4d x = ata.ldlt().solve(aty);
  ElementParams e;
  e.position = m + x.head<3>();
  e.direction = Eigen::Vector3d::UnitZ();
  e.radius = std::sqrt(x(3) + x.head<3>().squaredNorm());
  return e;
}

std::uint64_t seedFor(DataKind kind, std::size_t n) {
  return 0x5EEDULL * 1000003ULL + static_cast<std::uint64_t>(kind) * 7919ULL + n;
}

}  // namespace

const char* dataKindName(DataKind kind) {
  switch (kind) {
    case DataKind::Plane: return "plane";
    case DataKind::Sphere: return "sphere";
    case DataKind::Cylinder: return "cylinder";
    case DataKind::Roundness: return "roundness";
    case DataKind::Flatness: return "flatness";
  }
  return "?";
}

DataSet generate(DataKind kind, std::size_t n) {
  Rng rng(seedFor(kind, n));
  DataSet d;
  d.kind = kind;
  d.points.reserve(n);
  switch (kind) {
    case DataKind::Plane:
    case DataKind::Flatness: {
      // 200 x 200 mm square around (500, -300, 200), normal tilted ~2 deg.
      const Eigen::Vector3d p0(500.0, -300.0, 200.0);
      const Eigen::Vector3d w = Eigen::Vector3d(0.02, -0.03, 1.0).normalized();
      Eigen::Vector3d u, v;
      frame(w, u, v);
      for (std::size_t i = 0; i < n; ++i) {
        const double s = rng.uniform(-100.0, 100.0);
        const double t = rng.uniform(-100.0, 100.0);
        double dev = 0.0;
        if (kind == DataKind::Plane) {
          dev = 1e-3 * rng.gauss();  // 1 um noise
        } else {
          // 3 um saddle + 1 um wave + 0.5 um noise: a form the zone must straddle.
          dev = 3e-3 * (s / 100.0) * (t / 100.0) +
                1e-3 * std::cos(std::numbers::pi * s / 100.0) + 0.5e-3 * rng.gauss();
        }
        d.points.push_back(p0 + s * u + t * v + dev * w);
      }
      const Eigen::Vector3d c = centroid(d.points);
      d.truth.position = c - (c - p0).dot(w) * w;  // foot of the centroid
      d.truth.direction = w;
      d.start = d.truth;  // the plane fits are closed-form; no start is used
      break;
    }
    case DataKind::Sphere: {
      // Upper hemisphere, r = 25 mm, uniform over the area; radial 1 um noise.
      const Eigen::Vector3d c(500.123, -300.456, 200.789);
      const double r = 25.0;
      for (std::size_t i = 0; i < n; ++i) {
        const double z = rng.uniform();
        const double phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        const Eigen::Vector3d e(s * std::cos(phi), s * std::sin(phi), z);
        d.points.push_back(c + (r + 1e-3 * rng.gauss()) * e);
      }
      d.truth.position = c;
      d.truth.radius = r;
      d.start = algebraicSphere(d.points);
      break;
    }
    case DataKind::Cylinder: {
      // Full 360 deg, r = 20 mm, 100 mm long, axis tilted ~5.4 deg; radial 1 um noise.
      const Eigen::Vector3d a0(500.25, -300.5, 200.75);
      const Eigen::Vector3d w = Eigen::Vector3d(0.05, -0.08, 1.0).normalized();
      const double r = 20.0;
      Eigen::Vector3d u, v;
      frame(w, u, v);
      d.normals.reserve(n);
      for (std::size_t i = 0; i < n; ++i) {
        const double t = rng.uniform(-50.0, 50.0);
        const double phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const Eigen::Vector3d e = std::cos(phi) * u + std::sin(phi) * v;
        d.points.push_back(a0 + t * w + (r + 1e-3 * rng.gauss()) * e);
        d.normals.push_back(e);  // exact normal of the generating cylinder
      }
      const Eigen::Vector3d c = centroid(d.points);
      d.truth.position = a0 + (c - a0).dot(w) * w;  // axis point nearest the centroid
      d.truth.direction = w;
      d.truth.radius = r;
      // Start: axis point off by ~0.27 mm, axis tilted ~0.45 deg, radius +0.1 mm.
      d.start.position = d.truth.position + Eigen::Vector3d(0.2, -0.15, 0.1);
      d.start.direction = (w + 0.006 * u + 0.005 * v).normalized();
      d.start.radius = r + 0.1;
      break;
    }
    case DataKind::Roundness: {
      // Circle in z = 0, r = 25 mm: 2 um 3-lobe + 1 um 5-lobe + 0.5 um noise.
      const Eigen::Vector3d c(500.123, -300.456, 0.0);
      const double r = 25.0;
      for (std::size_t i = 0; i < n; ++i) {
        const double th =
            2.0 * std::numbers::pi * (static_cast<double>(i) + rng.uniform()) / static_cast<double>(n);
        const double dev = 2e-3 * std::cos(3.0 * th + 0.4) + 1e-3 * std::cos(5.0 * th + 1.1) +
                           0.5e-3 * rng.gauss();
        d.points.push_back(c + (r + dev) * Eigen::Vector3d(std::cos(th), std::sin(th), 0.0));
      }
      d.truth.position = c;
      d.truth.radius = r;
      d.start = d.truth;
      break;
    }
  }
  return d;
}

void writeDataSet(const std::string& path, const DataSet& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  unsigned char header[kHeaderBytes] = {};
  std::memcpy(header, kMagic, 8);
  const auto kind = static_cast<std::uint32_t>(data.kind);
  const std::uint32_t has_normals = data.normals.empty() ? 0u : 1u;
  const std::uint64_t n = data.points.size();
  std::memcpy(header + 8, &kind, 4);
  std::memcpy(header + 12, &has_normals, 4);
  std::memcpy(header + 16, &n, 8);
  auto put = [&](std::size_t offset, const ElementParams& e) {
    const double v[8] = {e.position.x(),  e.position.y(),  e.position.z(), e.direction.x(),
                         e.direction.y(), e.direction.z(), e.radius,       0.0};
    std::memcpy(header + offset, v, sizeof v);
  };
  put(24, data.truth);
  put(88, data.start);
  out.write(reinterpret_cast<const char*>(header), kHeaderBytes);
  out.write(reinterpret_cast<const char*>(data.points.data()),
            static_cast<std::streamsize>(n * sizeof(Eigen::Vector3d)));
  if (has_normals) {
    if (data.normals.size() != n) throw std::runtime_error(path + ": normals/points size mismatch");
    out.write(reinterpret_cast<const char*>(data.normals.data()),
              static_cast<std::streamsize>(n * sizeof(Eigen::Vector3d)));
  }
  if (!out) throw std::runtime_error(path + ": write failed");
}

DataSet readDataSet(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open (run probeloop_bench_data first)");
  unsigned char header[kHeaderBytes];
  if (!in.read(reinterpret_cast<char*>(header), kHeaderBytes) ||
      std::memcmp(header, kMagic, 8) != 0)
    throw std::runtime_error(path + ": not a PLBENCH1 point file");
  DataSet d;
  std::uint32_t kind = 0, has_normals = 0;
  std::uint64_t n = 0;
  std::memcpy(&kind, header + 8, 4);
  std::memcpy(&has_normals, header + 12, 4);
  std::memcpy(&n, header + 16, 8);
  d.kind = static_cast<DataKind>(kind);
  auto get = [&](std::size_t offset, ElementParams& e) {
    double v[8];
    std::memcpy(v, header + offset, sizeof v);
    e.position = Eigen::Vector3d(v[0], v[1], v[2]);
    e.direction = Eigen::Vector3d(v[3], v[4], v[5]);
    e.radius = v[6];
  };
  get(24, d.truth);
  get(88, d.start);
  d.points.resize(n);
  if (!in.read(reinterpret_cast<char*>(d.points.data()),
               static_cast<std::streamsize>(n * sizeof(Eigen::Vector3d))))
    throw std::runtime_error(path + ": truncated point block");
  if (has_normals) {
    d.normals.resize(n);
    if (!in.read(reinterpret_cast<char*>(d.normals.data()),
                 static_cast<std::streamsize>(n * sizeof(Eigen::Vector3d))))
      throw std::runtime_error(path + ": truncated normal block");
  }
  return d;
}

}  // namespace probeloop::bench
