// Internal to the least-squares fits (least_squares.hpp is the public contract): the shared
// checks, the fused Gauss-Newton / Levenberg-Marquardt engine and the result assembly.
// One translation unit per element family includes this header (ls_lines_planes.cpp,
// ls_circle.cpp, ls_sphere.cpp, ls_axis.cpp), so the templates compile in parallel.
//
// The engine's pass over the points (why it is fast and still accurate):
// - Each model gives one row per point: J_i = d r_i / d(local parameters) and r_i, the signed
//   orthogonal distance, from a kernel written once for a scalar and for four points in a
//   GCC vector (Quad). One pass accumulates the upper triangle of [J r]^T [J r]
//   (J^T J, J^T r and the sum of squares) and the residual range, in partial sums of
//   kBlock rows (rounding grows like (B + n / B) eps instead of n eps). The pass exists for
//   AVX2 (one register per Quad) and SSE2 (two), chosen at run time, with the same IEEE
//   operations per lane, so the fits are bit-identical on either CPU. The row kernels
//   take |v| and 1 / |v| as |v| / |v|^2, and the pass computes the next row before it adds
//   this one's products: both keep the square root's latency off the critical path.
// - On scans (more than kDenseMax points), once the steps are small, a Gauss-Newton trial
//   state is evaluated by a chord pass: J^T J kept from the last full pass, only J^T r, the
//   sum of squares and the range summed (accumulateGradient). The running sums of J^T J are
//   what a full pass spends its time on; the fixed point J^T r = 0 is the same.
// - The step is solved from the Cholesky factor of J^T J (R = L^T, Q^T r = L^-1 J^T r).
//   The fixed point J^T r = 0 does not depend on the solve; only the rate does. When the
//   equilibrated J^T J is ill-conditioned (short arcs, small caps, partial cylinders) and the
//   set is small enough (kDenseMax), the solution is polished by LM steps solved by
//   Householder QR of [J r] itself, whose steps keep their digits (condition of J, not of
//   J^T J), and the covariance comes from that R.
// - The pass that accepts the final state also carries the statistics the result needs
//   (sum of squares, residual range), so a fit that stores no residuals reads the points
//   once per iteration and never again.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

#include "geometry/least_squares.hpp"

namespace probeloop::geometry::ls {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
template <int P>
using Vec = Eigen::Matrix<double, P, 1>;
template <int P>
using Mat = Eigen::Matrix<double, P, P>;
using Points2 = std::vector<Vector2d>;

constexpr double kPi = std::numbers::pi;

// Points closer than this are the same point (mm).
constexpr double kCoincidentMm = 1e-9;
// Points count as collinear (coplanar) when their RMS distance from the best line (plane)
// is below kRankTol * max(RMS size, 1 mm): beyond that the orientation is lost to rounding.
constexpr double kRankTol = 1e-7;
// Sets up to this size may be polished with QR on the full n x p Jacobian.
constexpr std::size_t kDenseMax = 4096;
// Condition number of the equilibrated J^T J beyond which a small set is polished by QR:
// the normal-equation step then keeps fewer than 16 - log10(1e6) = 10 digits.
constexpr double kPolishCondition = 1e6;
// Rows per partial sum: rounding of the sums grows like (B + n / B) eps instead of n eps.
constexpr std::size_t kBlock = 1024;
// Points used to compare the starts of cylinder and cone fits, and to bring a start close
// (coarse stage) before the full set is iterated on.
constexpr std::size_t kStartSample = 2000;
// Sets above this size first converge on a subsample of kStartSample points.
constexpr std::size_t kCoarseMin = 16 * kStartSample;
// Convergence: dimensionless step (mm / data size, rad), relative gradient |Q^T r| / |r|.
constexpr double kStepTol = 1e-12;
constexpr double kGradTol = 1e-12;
// Largest step (as a displacement at the data's extent, mm) taken without another pass on
// the strength of the contraction estimate: it bounds how far the residual range of the last
// pass can be from that of the reported element.
constexpr double kUnverifiedStepMm = 1e-8;
// Chord passes (chordLinearisation) are taken while the steps since the last full pass add up
// to at most this (dimensionless, as kStepTol): J^T J has then changed by about as little.
constexpr double kChordStep = 1e-4;
// Rounding allowance of a sum of squares when comparing two of them.
constexpr double kSsrSlack = 1e-13;
// Largest condition number of the column-equilibrated J^T J at the solution; beyond it a
// parameter (typically the radius of a short arc or small cap) is not determined.
constexpr double kMaxCondition = 1e14;
// A cone with a smaller half angle is a cylinder (its direction sign is undefined).
constexpr double kMinHalfAngle = 1e-7;

// ---------------------------------------------------------------------------------------
// Messages and small geometry (ls_checks.cpp)

std::string num(double v, int digits = 3);
std::string um(double mm);
std::string degrees(double rad);
std::string name(ElementKind k);
[[noreturn]] void fail(const std::string& message);
bool isPlanar(ElementKind k);
// Unit vector with its largest-magnitude component positive (elements.hpp).
Vector3d canonical(const Vector3d& d);
// Rows e1, e2, e3 = d of a rotation.
Matrix3d frameOf(const Vector3d& d);
// Angle covered by 2D directions seen from the origin: 2 pi minus the largest gap.
double angularSpan(std::vector<double> angles);

// ---------------------------------------------------------------------------------------
// Input checks and moments (ls_checks.cpp)

void checkOptions(ElementKind kind, const LeastSquaresOptions& o);
void checkCount(ElementKind kind, const Points3& pts);

struct Moments {
  std::size_t n = 0;
  Vector3d centroid = Vector3d::Zero();
  Matrix3d cov = Matrix3d::Zero();  // mean of (p - c)(p - c)^T
};
Moments computeMoments(ElementKind kind, const Points3& pts);

struct Axes {
  Vector3d value;  // variances along the principal axes, ascending, clamped at 0
  Matrix3d vec;    // columns: unit principal axes
};
Axes principalAxes(const Moments& m);

// RMS distance of the points from their centroid.
double rmsSize(const Moments& m);
double maxDistanceFromLine(const Points3& pts, const Vector3d& c, const Vector3d& d, bool planar);
// Throws when two points lie within kCoincidentMm (in x, y for the planar kinds). Expected
// O(n): points are hashed by their cell of a 1 nm grid (neighbour cells are looked at only
// for a point within kCoincidentMm of a cell face).
void checkDuplicates(ElementKind kind, const Points3& pts);
void checkNotCoincident(ElementKind kind, const Axes& ax, std::size_t n);
void checkNotCollinear(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                       const std::string& need, const std::string& fix);
void checkNotCoplanar(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                      const std::string& need, const std::string& fix);
// Checks shared by the plane and the circle's plane.
void checkPlaneDetermined(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax);
// Local covariance (offset, two tilts) of the LS plane through principal axes.
Eigen::Vector3d planeLocalCovariance(const Axes& ax, std::size_t n);

// Residual statistics of a fit whose final pass already gave them.
struct ResidualStats {
  double ssr = 0.0;
  double min = 0.0;
  double max = 0.0;
};

// The result: residuals from signedDistance (options.keep_residuals) or the statistics of
// the fit's final pass (stats; one pass over the points when absent).
FitResult makeResult(const Element& e, const Points3& pts, int free_parameters,
                     std::vector<std::string> names, const Eigen::MatrixXd& cov, int iterations,
                     const LeastSquaresOptions& o, const ResidualStats* stats = nullptr);

// Centre for a known radius R: points of mean squared distance s2 from their centroid m
// put it at sqrt(R^2 - s2) from m (sum |p - c|^2 = n s2 + n |m - c|^2 on an exact circle);
// the side is taken from the free-radius start.
template <class V>
V knownRadiusCentre(const V& mean, double s2, const V& free_centre, double radius, const V& side) {
  V u = free_centre - mean;
  if (!(u.norm() > 0.0)) u = side;
  return mean + u.normalized() * std::sqrt(std::max(radius * radius - s2, 0.0));
}

// ---------------------------------------------------------------------------------------
// Row kernels: one point (double) or four (Quad, Ymm) at once

// The passes over the points (the fits' rows, the moments, the plane's residuals) run four
// points at a time, in one of two versions chosen at run time: for CPUs with AVX2 (compiled
// with [[gnu::target("avx2")]], a Quad in one ymm register) and for the others (two SSE2
// registers). Both do the same IEEE operations per lane in the same order, with no FMA
// (-ffp-contract=off for this library), so a fit is the same to the last bit on either CPU;
// ls_engine_test compares them.
//
// Whether the AVX2 versions run: the CPU has AVX2 and the default versions were not asked for
// (defaultPassesOnly, for the tests).
inline std::atomic<bool> defaultPassesOnly{false};
inline bool useAvx2Passes() {
  static const bool avx2 = [] {
    __builtin_cpu_init();  // in case the first fit runs in a static constructor
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2 && !defaultPassesOnly.load(std::memory_order_relaxed);
}

// Four points in the four lanes of a GCC vector: two SSE2 registers in the default pass, one
// AVX register in the AVX2 pass (as Ymm below).
#pragma GCC diagnostic push
// A function taking or returning a Quad (or Ymm) by value has a different calling convention
// in AVX2 code (ymm registers) than in default code (memory): every such helper is
// always_inline (also at -O0), so no call ever crosses that boundary; gcc's -Wpsabi note
// about it is silenced.
#pragma GCC diagnostic ignored "-Wpsabi"
using Quad = double __attribute__((vector_size(32)));
using QuadHalf = double __attribute__((vector_size(16)));
[[gnu::always_inline]] inline Quad sqrtOf(Quad x) {
  const QuadHalf lo = __builtin_ia32_sqrtpd(QuadHalf{x[0], x[1]});
  const QuadHalf hi = __builtin_ia32_sqrtpd(QuadHalf{x[2], x[3]});
  return Quad{lo[0], lo[1], hi[0], hi[1]};
}
[[gnu::always_inline]] inline Quad atLeast(Quad x, double floor) {
  const Quad f = {floor, floor, floor, floor};
  return x > f ? x : f;  // a NaN gives the floor; its residual still makes the sums NaN
}
[[gnu::always_inline]] inline Quad reciprocal(Quad x) { return 1.0 / x; }
[[gnu::always_inline]] inline Quad lowerOf(Quad a, Quad b) { return a < b ? a : b; }
[[gnu::always_inline]] inline Quad higherOf(Quad a, Quad b) { return a > b ? a : b; }

// A Quad as the lane type of the AVX2 pass: a type of its own so that the row kernels,
// written once for any lane type, take its four square roots with one 256-bit vsqrtpd. Two
// 128-bit sqrtpd take twice its time on the AVX2 cores measured (docs/performance.md), and
// the compiler does not merge them. A square root is correctly rounded either way, and every
// other operation is Quad's, so the two passes give the same bits.
struct Ymm {
  Quad v;
  [[gnu::always_inline]] double operator[](int k) const { return v[k]; }
  [[gnu::always_inline]] Ymm& operator+=(Ymm o) {
    v += o.v;
    return *this;
  }
};
[[gnu::always_inline]] inline Ymm operator-(Ymm a) { return {-a.v}; }
[[gnu::always_inline]] inline Ymm operator+(Ymm a, Ymm b) { return {a.v + b.v}; }
[[gnu::always_inline]] inline Ymm operator-(Ymm a, Ymm b) { return {a.v - b.v}; }
[[gnu::always_inline]] inline Ymm operator*(Ymm a, Ymm b) { return {a.v * b.v}; }
[[gnu::always_inline]] inline Ymm operator-(Ymm a, double b) { return {a.v - b}; }
[[gnu::always_inline]] inline Ymm operator*(Ymm a, double b) { return {a.v * b}; }
[[gnu::always_inline]] inline Ymm operator*(double a, Ymm b) { return {a * b.v}; }
[[gnu::always_inline]] inline Ymm sqrtOf(Ymm x) {
#if defined(__clang__)
  return {sqrtOf(x.v)};  // clang checks the constraint before inlining; same bits
#else
  // Only ever inlined into the AVX2 pass (everything on the way is always_inline), where a
  // Ymm lives in one ymm register.
  const Quad in = x.v;
  Quad out;
  asm("vsqrtpd {%1, %0|%0, %1}" : "=x"(out) : "x"(in));  // AT&T | Intel syntax
  return {out};
#endif
}
[[gnu::always_inline]] inline Ymm atLeast(Ymm x, double floor) { return {atLeast(x.v, floor)}; }
[[gnu::always_inline]] inline Ymm reciprocal(Ymm x) { return {1.0 / x.v}; }
[[gnu::always_inline]] inline Ymm lowerOf(Ymm a, Ymm b) { return {lowerOf(a.v, b.v)}; }
[[gnu::always_inline]] inline Ymm higherOf(Ymm a, Ymm b) { return {higherOf(a.v, b.v)}; }

inline double sqrtOf(double x) { return std::sqrt(x); }
inline double atLeast(double x, double floor) { return std::max(x, floor); }
inline double reciprocal(double x) { return 1.0 / x; }
template <class T>
[[gnu::always_inline]] inline T constant(double x) {
  if constexpr (std::is_same_v<T, Quad>)
    return Quad{x, x, x, x};
  else if constexpr (std::is_same_v<T, Ymm>)
    return Ymm{Quad{x, x, x, x}};
  else
    return x;
}

// Coordinate c of point i (and the next three for a Quad or Ymm) of points stored as `stride`
// doubles each.
template <class T>
[[gnu::always_inline]] inline T gather(const double* base, std::size_t i, std::size_t stride, int c) {
  if constexpr (std::is_same_v<T, Quad>)
    return Quad{base[i * stride + c], base[(i + 1) * stride + c], base[(i + 2) * stride + c],
                base[(i + 3) * stride + c]};
  else if constexpr (std::is_same_v<T, Ymm>)
    return Ymm{gather<Quad>(base, i, stride, c)};
  else
    return base[i * stride + c];
}

// |v| and 1 / |v| from |v|^2, as |v| / |v|^2: the square root and the division do not wait
// for each other (1 / sqrt(s) chains them), which is what bounded the row kernels' time.
// A zero length gives 1 / |v| = 0, so its Jacobian row is 0, not NaN. Below |v| = 1.5e-154 mm
// (|v|^2 under the smallest normal double) 1 / |v| comes out too small by |v|^2 / DBL_MIN;
// a point that close to a centre or an axis has no direction to give anyway.
template <class T>
struct LengthAndInverse {
  T length, inverse;
};
template <class T>
[[gnu::always_inline]] inline LengthAndInverse<T> lengthAndInverse(T squared) {
  const T length = sqrtOf(squared);
  return {length, length * reciprocal(atLeast(squared, std::numeric_limits<double>::min()))};
}

// ---------------------------------------------------------------------------------------
// Reduced least-squares problem

template <int P>
struct Linearisation {
  Mat<P> R = Mat<P>::Zero();    // J = Q R (or R^T R = J^T J), upper triangular
  Vec<P> qtr = Vec<P>::Zero();  // Q^T r (R^-T J^T r)
  double ssr = 0.0;
  double rmin = 0.0, rmax = 0.0;  // residual range
  bool ok = false;
  bool dense = false;  // R from QR of J itself
  bool chord = false;  // R kept from an earlier state (chordLinearisation)
};

// Sums of a pass over the rows [J_i r_i], and the residual range.
template <int K>
struct RowSums {
  std::array<double, K> s{};
  double rmin = std::numeric_limits<double>::infinity();
  double rmax = -std::numeric_limits<double>::infinity();
};

// What a full pass sums per row: the upper triangle of [J r]^T [J r] in row-major order.
template <int P>
struct AllProducts {
  static constexpr int K = (P + 1) * (P + 2) / 2;
  template <class T>
  [[gnu::always_inline]] static void add(std::array<T, K>& acc, const std::array<T, P + 1>& v) {
    int k = 0;
#pragma GCC unroll 8
    for (int a = 0; a <= P; ++a) {
#pragma GCC unroll 8
      for (int b = a; b <= P; ++b) acc[k++] += v[a] * v[b];
    }
  }
};

// What a chord pass sums per row: J^T r and r^T r, the last column of [J r]^T [J r]. With
// P + 1 running sums instead of (P + 1)(P + 2) / 2 it costs a third of a full pass.
template <int P>
struct GradientProducts {
  static constexpr int K = P + 1;
  template <class T>
  [[gnu::always_inline]] static void add(std::array<T, K>& acc, const std::array<T, P + 1>& v) {
#pragma GCC unroll 8
    for (int a = 0; a <= P; ++a) acc[a] += v[a] * v[P];
  }
};

template <int P>
using NormalSums = RowSums<AllProducts<P>::K>;
template <int P>
using GradientSums = RowSums<GradientProducts<P>::K>;

// One pass: the model's rows at state s, summed in blocks, four points at a time (T = Quad
// or Ymm).
template <class T, class Products, class Model>
[[gnu::always_inline]] inline RowSums<Products::K> sumRowsWith(const Model& model,
                                                               const typename Model::State& s) {
  constexpr int P = Model::P;
  constexpr int K = Products::K;
  const auto pre = model.prepare(s);
  const std::size_t n = model.count();
  RowSums<K> out;
  const double inf = std::numeric_limits<double>::infinity();
  T lo = constant<T>(inf);
  T hi = constant<T>(-inf);
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    std::array<T, K> acc;
    acc.fill(constant<T>(0.0));
    std::size_t i = b0;
    // Software-pipelined by one row of four: the next row's square root is issued before this
    // row's products, so its latency overlaps them (12 % off a full cylinder pass). The sums
    // are taken in the same order as without it.
    if (i + 4 <= b1) {
      std::array<T, P + 1> v;
      model.template row<T>(pre, i, v);
      for (i += 4; i + 4 <= b1; i += 4) {
        std::array<T, P + 1> next;
        model.template row<T>(pre, i, next);
        Products::add(acc, v);
        lo = lowerOf(lo, v[P]);
        hi = higherOf(hi, v[P]);
        v = next;
      }
      Products::add(acc, v);
      lo = lowerOf(lo, v[P]);
      hi = higherOf(hi, v[P]);
    }
    std::array<double, K> tail{};
    for (; i < b1; ++i) {
      std::array<double, P + 1> v;
      model.template row<double>(pre, i, v);
      Products::add(tail, v);
      out.rmin = std::min(out.rmin, v[P]);
      out.rmax = std::max(out.rmax, v[P]);
    }
    for (int k = 0; k < K; ++k)
      out.s[k] += ((acc[k][0] + acc[k][1]) + (acc[k][2] + acc[k][3])) + tail[k];
  }
  out.rmin = std::min({out.rmin, lo[0], lo[1], lo[2], lo[3]});
  out.rmax = std::max({out.rmax, hi[0], hi[1], hi[2], hi[3]});
  return out;
}

// The two versions of the pass. The 15-28 running sums of [J r]^T [J r] and the square roots
// are what it spends its time on, and AVX2 halves their instructions (docs/performance.md).
template <class Products, class Model>
[[gnu::target("avx2")]] RowSums<Products::K> sumRowsAvx2(const Model& model,
                                                         const typename Model::State& s) {
  return sumRowsWith<Ymm, Products>(model, s);
}
template <class Products, class Model>
RowSums<Products::K> sumRowsDefault(const Model& model, const typename Model::State& s) {
  return sumRowsWith<Quad, Products>(model, s);
}
template <class Products, class Model>
RowSums<Products::K> sumRows(const Model& model, const typename Model::State& s) {
  return useAvx2Passes() ? sumRowsAvx2<Products>(model, s) : sumRowsDefault<Products>(model, s);
}

// The full pass and the chord pass.
template <class Model>
NormalSums<Model::P> accumulate(const Model& model, const typename Model::State& s) {
  return sumRows<AllProducts<Model::P>>(model, s);
}
template <class Model>
GradientSums<Model::P> accumulateGradient(const Model& model, const typename Model::State& s) {
  return sumRows<GradientProducts<Model::P>>(model, s);
}
#pragma GCC diagnostic pop

// Cholesky of the accumulated J^T J.
template <int P>
Linearisation<P> fromNormalSums(const NormalSums<P>& sums) {
  Mat<P + 1> t = Mat<P + 1>::Zero();
  int k = 0;
  for (int a = 0; a <= P; ++a)
    for (int b = a; b <= P; ++b) t(a, b) = sums.s[k++];
  Linearisation<P> out;
  out.rmin = sums.rmin;
  out.rmax = sums.rmax;
  const Mat<P> jtj = t.template topLeftCorner<P, P>().template selfadjointView<Eigen::Upper>();
  Eigen::LLT<Mat<P>> llt(jtj);
  if (llt.info() != Eigen::Success) return out;
  out.R = llt.matrixU();
  out.qtr = llt.matrixL().solve(Vec<P>(t.col(P).template head<P>()));
  out.ssr = t(P, P);
  out.ok = out.R.allFinite() && out.qtr.allFinite() && std::isfinite(out.ssr) &&
           (out.R.diagonal().array() != 0.0).all();
  return out;
}

// Householder QR of the full [J r] (blocked sum of squares kept for comparability).
template <class Model>
Linearisation<Model::P> denseLinearisation(const Model& model, const typename Model::State& s) {
  constexpr int P = Model::P;
  const auto pre = model.prepare(s);
  const std::size_t n = model.count();
  // At least P + 1 rows so that the R factor of [J r] is square; extra rows are zero.
  Eigen::Matrix<double, Eigen::Dynamic, P + 1> a =
      Eigen::Matrix<double, Eigen::Dynamic, P + 1>::Zero(
          static_cast<Eigen::Index>(std::max<std::size_t>(n, P + 1)), P + 1);
  Linearisation<P> out;
  out.rmin = std::numeric_limits<double>::infinity();
  out.rmax = -out.rmin;
  double block = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    std::array<double, P + 1> v;
    model.template row<double>(pre, i, v);
    for (int c = 0; c <= P; ++c) a(static_cast<Eigen::Index>(i), c) = v[c];
    block += v[P] * v[P];
    out.rmin = std::min(out.rmin, v[P]);
    out.rmax = std::max(out.rmax, v[P]);
    if ((i + 1) % kBlock == 0 || i + 1 == n) out.ssr += block, block = 0.0;
  }
  Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, P + 1>> qr(a);
  const Mat<P + 1> ra =
      qr.matrixQR().template topRows<P + 1>().template triangularView<Eigen::Upper>();
  out.R = ra.template topLeftCorner<P, P>();
  out.qtr = ra.col(P).template head<P>();
  out.dense = true;
  out.ok = out.R.allFinite() && out.qtr.allFinite() && std::isfinite(out.ssr) &&
           (out.R.diagonal().array() != 0.0).all();
  return out;
}

template <class Model>
Linearisation<Model::P> linearise(const Model& model, const typename Model::State& s, bool dense) {
  if (!dense) {
    Linearisation<Model::P> l = fromNormalSums<Model::P>(accumulate(model, s));
    if (l.ok) return l;
    // J^T J lost definiteness to rounding: the full Jacobian still may have full rank.
  }
  return denseLinearisation(model, s);
}

// The chord linearisation at s (simplified Gauss-Newton): J^T J kept from `base` (its
// Cholesky factor R), J^T r, the sum of squares and the range from a gradient pass at s.
// The step -(J^T J)^-1 J^T r then converges linearly at about the relative change of J^T J
// since base, and its fixed point is still J^T r = 0: the same solution.
template <class Model>
Linearisation<Model::P> chordLinearisation(const Model& model, const typename Model::State& s,
                                           const Linearisation<Model::P>& base) {
  constexpr int P = Model::P;
  const GradientSums<P> g = accumulateGradient(model, s);
  Linearisation<P> out;
  out.R = base.R;
  out.qtr = base.R.transpose().template triangularView<Eigen::Lower>().solve(
      Vec<P>(Eigen::Map<const Vec<P>>(g.s.data())));
  out.ssr = g.s[P];
  out.rmin = g.rmin;
  out.rmax = g.rmax;
  out.ok = base.ok && out.qtr.allFinite() && std::isfinite(out.ssr);
  out.chord = true;
  return out;
}

// Whether J^T J at `base` still describes the parameters at `next`: the axis models'
// parameters live in a frame rebuilt every step, which turns by 90 degrees or more when the
// axis crosses the xy plane (frameOf); the others have fixed parameters.
template <class Model>
bool sameParameters(const Model& model, const typename Model::State& base,
                    const typename Model::State& next) {
  if constexpr (requires { model.sameFrame(base, next); })
    return model.sameFrame(base, next);
  else
    return true;
}

template <int P>
Vec<P> columnNorms(const Mat<P>& r) {
  return r.colwise().norm().transpose();
}

// argmin |R d + qtr|^2 + lambda |D d|^2, by QR of the small stacked matrix [R; sqrt(lambda) D]
// (MINPACK's lmpar/qrsolv idea, More 1978).
template <int P>
Vec<P> dampedStep(const Linearisation<P>& l, const Vec<P>& d, double lambda) {
  if (lambda == 0.0) return -l.R.template triangularView<Eigen::Upper>().solve(l.qtr);
  Eigen::Matrix<double, 2 * P, P> a;
  a.template topRows<P>() = l.R;
  a.template bottomRows<P>() = (std::sqrt(lambda) * d).asDiagonal();
  Vec<2 * P> b = Vec<2 * P>::Zero();
  b.template head<P>() = -l.qtr;
  return a.householderQr().solve(b);
}

template <class Model>
struct LmRun {
  typename Model::State state{};
  Linearisation<Model::P> lin;
  int iterations = 0;
  bool converged = false;
};

// Levenberg-Marquardt from `start`: one pass over the points per trial state (the pass that
// accepts a state is its linearisation for the next step).
template <class Model>
LmRun<Model> levenbergMarquardt(const Model& model, const typename Model::State& start,
                                int max_iterations, bool dense = false) {
  constexpr int P = Model::P;
  LmRun<Model> run;
  run.state = start;
  if (!model.valid(start)) return run;
  run.lin = linearise(model, start, dense);
  if (!run.lin.ok) return run;
  Vec<P> scale = columnNorms(run.lin.R).cwiseMax(1e-300);
  double lambda = 0.0;
  double previous_size = std::numeric_limits<double>::infinity();
  double since_full = 0.0;  // sum of the steps since run.lin's J^T J was summed
  typename Model::State full_at = start;  // where it was summed
  while (run.iterations < max_iterations) {
    ++run.iterations;
    if (run.lin.qtr.norm() <= kGradTol * std::sqrt(run.lin.ssr)) {
      run.converged = true;  // residuals orthogonal to the columns of J: stationary
      break;
    }
    bool accepted = false;
    for (int tries = 0; tries < 60 && !accepted && !run.converged; ++tries) {
      const Vec<P> step = dampedStep(run.lin, scale, lambda);
      const double size =
          step.allFinite() ? model.stepSize(step) : std::numeric_limits<double>::infinity();
      // The last Gauss-Newton step is taken without another pass over the points when it
      // is negligible (<= kStepTol), and on a large set (a scan) also when it moves the
      // element by at most kUnverifiedStepMm (10 pm) at the data's extent and the iteration
      // contracts by theta = size / previous size per step so that the solution is then
      // about theta * size <= kStepTol away (Deuflhard's a-posteriori estimate). The sum of
      // squares moves by the step's predicted decrease |Q^T r|^2; the residual range (form)
      // of the last pass by at most the step: below 10 pm. Small sets, where a pass costs
      // little, verify a contracted step instead (that verification is worth the last
      // digits against NIST's reference fits).
      if (lambda == 0.0 &&
          (size <= kStepTol ||
           (model.count() > kDenseMax && size * model.size <= kUnverifiedStepMm &&
            std::isfinite(previous_size) && size * (size / previous_size) <= kStepTol))) {
        const typename Model::State next = model.apply(run.state, step);
        if (model.valid(next)) {
          run.state = next;
          run.lin.ssr = std::max(run.lin.ssr - run.lin.qtr.squaredNorm(), 0.0);
          run.converged = true;
          break;
        }
      }
      if (std::isfinite(size)) {
        const typename Model::State next = model.apply(run.state, step);
        if (model.valid(next)) {
          const bool chord = !dense && lambda == 0.0 && model.count() > kDenseMax &&
                             since_full + size <= kChordStep && sameParameters(model, full_at, next);
          const Linearisation<P> l =
              chord ? chordLinearisation(model, next, run.lin) : linearise(model, next, dense);
          // Ties within the rounding of the sum of squares are accepted: close to the
          // solution a Gauss-Newton step changes the sum by less than its rounding error
          // and still moves the parameters by a meaningful amount. Each residual carries
          // a rounding error of about model.rounding (eps times the coordinates), so the
          // sum carries about 2 |r| sqrt(n) model.rounding.
          const double slack = kSsrSlack * run.lin.ssr +
                               2.0 * model.rounding *
                                   std::sqrt(static_cast<double>(model.count()) * run.lin.ssr);
          if (l.ok && l.ssr <= run.lin.ssr + slack) {
            const bool gauss_newton = lambda == 0.0;
            const bool insignificant = run.lin.ssr - l.ssr <= slack;
            const bool step_from_chord = run.lin.chord;
            run.state = next;
            run.lin = l;
            since_full = chord ? since_full + size : 0.0;
            if (!chord) full_at = next;
            scale = scale.cwiseMax(columnNorms(l.R));
            lambda = lambda < 1e-8 ? 0.0 : 0.1 * lambda;
            accepted = true;
            // Converged when the step is negligible, or when Gauss-Newton steps no longer
            // shrink while the sum of squares no longer changes: the rounding floor.
            // A chord step that did not halve says J^T J is stale, not that the floor is
            // reached: the next trial gets a full pass.
            if (size <= kStepTol)
              run.converged = true;
            else if (gauss_newton && insignificant && size > 0.5 * previous_size) {
              if (step_from_chord)
                since_full = std::numeric_limits<double>::infinity();
              else
                run.converged = true;
            }
            previous_size = gauss_newton ? size : std::numeric_limits<double>::infinity();
            break;
          }
        }
      }
      if (size <= kStepTol) run.converged = true;  // not even a rounding-size step helps
      lambda = lambda == 0.0 ? 1e-3 : 10.0 * lambda;
    }
    if (run.converged || !accepted) break;
  }
  return run;
}

// Condition number of the column-equilibrated J^T J and its most ill-determined
// parameter combination (right singular vector, equilibrated units).
template <int P>
struct Conditioning {
  double condition = std::numeric_limits<double>::infinity();
  Vec<P> weakest = Vec<P>::Zero();
};

template <int P>
Conditioning<P> conditioning(const Linearisation<P>& l) {
  Conditioning<P> c;
  if (!l.ok) return c;
  const Vec<P> norms = columnNorms(l.R);
  if ((norms.array() <= 0.0).any()) return c;
  // Eigenvalues of the equilibrated J^T J = S^T S, S = R D^-1 (the squared singular values
  // of S; the smallest carries an error of about eps times the largest, ample for a
  // threshold of 1e14).
  const Mat<P> scaled = l.R * norms.cwiseInverse().asDiagonal();
  Eigen::SelfAdjointEigenSolver<Mat<P>> es(scaled.transpose() * scaled);
  const double lmax = es.eigenvalues()(P - 1);
  const double lmin = es.eigenvalues()(0);
  c.condition = lmin > 0.0 ? lmax / lmin : std::numeric_limits<double>::infinity();
  c.weakest = es.eigenvectors().col(0);
  return c;
}

// A run whose normal equations are ill-conditioned, on a set small enough for it, polished
// with QR-solved steps from where it stopped, within what is left of the iteration budget.
// The polished run replaces it unless that would lose convergence.
template <class Model>
LmRun<Model> polished(const Model& model, LmRun<Model> run, int max_iterations) {
  if (run.lin.dense || !run.lin.ok || model.count() > kDenseMax) return run;
  if (conditioning(run.lin).condition <= kPolishCondition) return run;
  const int left = max_iterations - run.iterations;
  if (left < 1) return run;
  LmRun<Model> dense = levenbergMarquardt(model, run.state, left, true);
  if (!dense.lin.ok || (run.converged && !dense.converged)) return run;
  dense.iterations += run.iterations;
  return dense;
}

// (J^T J)^-1 = R^-1 R^-T.
template <int P>
Mat<P> inverseNormal(const Linearisation<P>& l) {
  const Mat<P> rinv = l.R.template triangularView<Eigen::Upper>().solve(Mat<P>::Identity());
  return rinv * rinv.transpose();
}

template <int P>
ResidualStats statsOf(const Linearisation<P>& l) {
  return {l.ssr, l.rmin, l.rmax};
}

// Every kStartSample-th part of a large set, evenly spread over its order.
Points3 strideSample(const Points3& pts, std::size_t count);

// ---------------------------------------------------------------------------------------
// The element families (one translation unit each)

FitResult fitLine2D(const Points3& pts, const Moments& m, const LeastSquaresOptions& o);
FitResult fitLine3D(const Points3& pts, const Moments& m, const Axes& ax,
                    const LeastSquaresOptions& o);
FitResult fitPlane(const Points3& pts, const Moments& m, const Axes& ax,
                   const LeastSquaresOptions& o);
FitResult fitCircle2D(const Points3& pts, const Moments& m, const LeastSquaresOptions& o);
FitResult fitCircle3D(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o);
FitResult fitSphereLs(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o);
FitResult fitCylinder(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o);
FitResult fitCone(const Points3& pts, const Moments& m, const Axes& ax,
                  const LeastSquaresOptions& o);

}  // namespace probeloop::geometry::ls
