// Least-squares fits of every element (contract in least_squares.hpp and elements.hpp).
//
// Algorithms, by kind:
// - line2d, line3d, plane: closed form. One pass accumulates the first and second moments
//   about a data point (blocked partial sums), then the eigenvectors of the 3x3 (2x2)
//   scatter matrix give the exact LS line/plane through the centroid (orthogonal
//   regression; Forbes, NPL DITC 140/89, sections 3-4; Shakarji, J. Res. NIST 103 (1998)).
// - circle2d: Taubin algebraic fit as the start (Chernov, "Circular and Linear Regression",
//   CRC 2010, ch. 5; his Newton form of CircleFitByTaubin), then Gauss-Newton /
//   Levenberg-Marquardt on the geometric distances |q - c| - r.
// - circle3d: the LS plane, then the 2D circle LS of the points projected on that plane
//   (what CMM software reports: the residuals are radial deviations in the circle's plane).
// - sphere: Kasa algebraic start (or options.start), then geometric LM, like fitSphere().
// - cylinder, cone: geometric LM in a local frame re-centred every iteration (Forbes
//   DITC 140/89 section 6; Shakarji 1998): rotate so the current axis is z, translate so the
//   axis point (foot of the data centroid) is the origin; the parameters are the axis offsets
//   x0, y0, the tilts a, b of the axis direction (a, b, 1), the radius there (and the half
//   angle psi for the cone). Starts: options.start if given; otherwise the three principal
//   axes and the best directions of a hemisphere grid scored by an algebraic fit for that
//   direction, each refined on a subsample, keeping the lowest sum of squares.
//
// Every LM step is solved from the R factor of J: Householder QR of [J r] when n <= 4096
// rows (accurate for ill-conditioned partial features), otherwise J^T J and J^T r are
// accumulated in one pass in blocks and factored by Cholesky (fast for 1e6+ points; the
// fixed point J^T r = 0 is the same, only the rate of convergence depends on the solve).
// The damped step min |R d + Q^T r|^2 + lambda |D d|^2 is solved by a QR of the small
// stacked matrix [R; sqrt(lambda) D] (MINPACK's lmpar/qrsolv idea, More 1978).
#include "geometry/least_squares.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace probeloop::geometry {
namespace {

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
// Duplicated points are searched for in sets up to this size (probed points, where a
// duplicate is a probing mistake and can leave a small set degenerate). Larger sets are
// scans, where repeated coordinates are legitimate samples; the rank and conditioning
// checks still catch a degenerate cloud.
constexpr std::size_t kDuplicateSearchMax = 20000;
// QR on the full n x p Jacobian up to this many rows, accumulated J^T J beyond.
constexpr std::size_t kDenseMax = 4096;
// Rows per partial sum: rounding of the sums grows like (B + n / B) eps instead of n eps.
constexpr std::size_t kBlock = 1024;
// Points used to compare the starts of cylinder and cone fits.
constexpr std::size_t kStartSample = 2000;
// Convergence: dimensionless step (mm / data size, rad), relative gradient |Q^T r| / |r|.
constexpr double kStepTol = 1e-12;
constexpr double kGradTol = 1e-12;
// Rounding allowance of a sum of squares when comparing two of them.
constexpr double kSsrSlack = 1e-13;
// Largest condition number of the column-equilibrated J^T J at the solution; beyond it a
// parameter (typically the radius of a short arc or small cap) is not determined.
constexpr double kMaxCondition = 1e14;
// A cone with a smaller half angle is a cylinder (its direction sign is undefined).
constexpr double kMinHalfAngle = 1e-7;

// ---------------------------------------------------------------------------------------
// Messages

std::string num(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}
std::string um(double mm) { return num(mm * 1000.0, 2) + " um"; }
std::string degrees(double rad) { return num(rad * 180.0 / kPi, 3) + " deg"; }
std::string name(ElementKind k) { return std::string(elementName(k)); }
[[noreturn]] void fail(const std::string& message) { throw GeometryError(message); }

bool isPlanar(ElementKind k) { return k == ElementKind::Line2D || k == ElementKind::Circle2D; }

// Unit vector with its largest-magnitude component positive (elements.hpp).
Vector3d canonical(const Vector3d& d) {
  int k = 0;
  d.cwiseAbs().maxCoeff(&k);
  return d(k) < 0.0 ? Vector3d(-d) : d;
}

// Rows e1, e2, e3 = d of a rotation (Duff et al., "Building an orthonormal basis,
// revisited", JCGT 6(1), 2017: continuous except at d.z = 0, no division by ~0).
Matrix3d frameOf(const Vector3d& d) {
  const double sign = std::copysign(1.0, d.z());
  const double a = -1.0 / (sign + d.z());
  const double b = d.x() * d.y() * a;
  Matrix3d u;
  u.row(0) << 1.0 + sign * d.x() * d.x() * a, sign * b, -sign * d.x();
  u.row(1) << b, sign + d.y() * d.y() * a, -d.y();
  u.row(2) = d.transpose();
  return u;
}

// Angle covered by 2D directions seen from the origin: 2 pi minus the largest gap.
double angularSpan(std::vector<double> angles) {
  if (angles.size() < 2) return 0.0;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2.0 * kPi - angles.back();
  for (std::size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
  return 2.0 * kPi - gap;
}

// ---------------------------------------------------------------------------------------
// Input checks and moments

void checkOptions(ElementKind kind, const LeastSquaresOptions& o) {
  if (o.max_iterations < 1)
    fail("least-squares " + name(kind) + ": max_iterations is " +
         std::to_string(o.max_iterations) + "; give at least 1 (default 100)");
  if (!o.fixed_radius_mm) return;
  if (kind != ElementKind::Circle2D && kind != ElementKind::Circle3D &&
      kind != ElementKind::Sphere && kind != ElementKind::Cylinder)
    fail("a known radius applies to circle, sphere and cylinder fits; a " + name(kind) +
         " has no single radius: drop the known radius");
  const double r = *o.fixed_radius_mm;
  if (!std::isfinite(r) || !(r > 0.0))
    fail("the known " + name(kind) + " radius must be a positive number of mm (got " + num(r) +
         "): give the nominal radius, or fit without a known radius");
}

void checkCount(ElementKind kind, const Points3& pts) {
  const int need = minimumPoints(kind);
  if (static_cast<long>(pts.size()) < need) {
    fail(name(kind) + " needs >= " + std::to_string(need) + " points; got " +
         std::to_string(pts.size()) + ": probe at least " +
         std::to_string(need - static_cast<long>(pts.size())) + " more points on the " +
         name(kind));
  }
}

struct Moments {
  std::size_t n = 0;
  Vector3d centroid = Vector3d::Zero();
  Matrix3d cov = Matrix3d::Zero();  // mean of (p - c)(p - c)^T
};

// One pass: sums of d and d d^T, d = p - shift, in blocks of kBlock partial sums.
template <bool Planar>
Moments momentsAbout(const Points3& pts, const Vector3d& shift) {
  const std::size_t n = pts.size();
  std::array<double, 9> t{};  // x y z xx xy xz yy yz zz
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
    for (std::size_t i = b0; i < b1; ++i) {
      const double x = pts[i].x() - shift.x();
      const double y = pts[i].y() - shift.y();
      const double z = Planar ? 0.0 : pts[i].z() - shift.z();
      sx += x;
      sy += y;
      sz += z;
      sxx += x * x;
      sxy += x * y;
      sxz += x * z;
      syy += y * y;
      syz += y * z;
      szz += z * z;
    }
    t[0] += sx, t[1] += sy, t[2] += sz, t[3] += sxx, t[4] += sxy;
    t[5] += sxz, t[6] += syy, t[7] += syz, t[8] += szz;
  }
  Moments m;
  m.n = n;
  const double inv = 1.0 / static_cast<double>(n);
  const Vector3d mean(t[0] * inv, t[1] * inv, t[2] * inv);
  m.centroid = shift + mean;
  m.cov << t[3] * inv, t[4] * inv, t[5] * inv,  //
      t[4] * inv, t[6] * inv, t[7] * inv,       //
      t[5] * inv, t[7] * inv, t[8] * inv;
  m.cov -= mean * mean.transpose();
  return m;
}

[[noreturn]] void reportNonFinite(ElementKind kind, const Points3& pts, bool planar) {
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vector3d& p = pts[i];
    const bool finite = planar ? p.head<2>().allFinite() : p.allFinite();
    if (!finite)
      fail(name(kind) + " point " + std::to_string(i + 1) + " is not finite (" + num(p.x()) +
           ", " + num(p.y()) + (planar ? "" : ", " + num(p.z())) +
           "): remove it or re-measure it");
  }
  fail(name(kind) + " point coordinates are too large to square in double precision: "
       "check the units (mm expected)");
}

Moments computeMoments(ElementKind kind, const Points3& pts) {
  const bool planar = isPlanar(kind);
  auto run = [&](Vector3d shift) {
    if (planar) shift.z() = 0.0;
    return planar ? momentsAbout<true>(pts, shift) : momentsAbout<false>(pts, shift);
  };
  Moments m = run(pts.front());
  if (!m.centroid.allFinite() || !m.cov.allFinite()) reportNonFinite(kind, pts, planar);
  // A data point as the shift keeps the cancellation in E[dd^T] - E[d]E[d]^T small; only
  // when that point lies far out from the rest is a second pass about the centroid needed.
  if ((pts.front() - m.centroid).head(planar ? 2 : 3).squaredNorm() > 1e4 * m.cov.trace())
    m = run(m.centroid);
  return m;
}

struct Axes {
  Vector3d value;  // variances along the principal axes, ascending, clamped at 0
  Matrix3d vec;    // columns: unit principal axes
};

Axes principalAxes(const Moments& m) {
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(m.cov);
  return {es.eigenvalues().cwiseMax(0.0), es.eigenvectors()};
}

double maxDistanceFromLine(const Points3& pts, const Vector3d& c, const Vector3d& d, bool planar) {
  double worst = 0.0;
  for (const auto& p : pts) {
    Vector3d v = p - c;
    if (planar) v.z() = 0.0;
    worst = std::max(worst, (v - d * d.dot(v)).norm());
  }
  return worst;
}

double maxDistanceFromPlane(const Points3& pts, const Vector3d& c, const Vector3d& n) {
  double worst = 0.0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(n.dot(p - c)));
  return worst;
}

void checkDuplicates(ElementKind kind, const Points3& pts, const Moments& m) {
  const std::size_t n = pts.size();
  if (n > kDuplicateSearchMax) return;
  const bool planar = isPlanar(kind);
  int axis = 0;
  m.cov.diagonal().head(planar ? 2 : 3).maxCoeff(&axis);  // sweep along the widest spread
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return pts[a](axis) < pts[b](axis) || (pts[a](axis) == pts[b](axis) && a < b);
  });
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      const Vector3d& p = pts[idx[a]];
      const Vector3d& q = pts[idx[b]];
      if (q(axis) - p(axis) > kCoincidentMm) break;
      const double d = planar ? (p - q).head<2>().norm() : (p - q).norm();
      if (d <= kCoincidentMm) {
        const std::size_t i = std::min(idx[a], idx[b]) + 1;
        const std::size_t j = std::max(idx[a], idx[b]) + 1;
        fail(name(kind) + " points " + std::to_string(i) + " and " + std::to_string(j) +
             " coincide" + (planar ? " in x, y" : "") +
             ": remove the duplicate (a repeated point counts twice in the fit)");
      }
    }
  }
}

// RMS distance of the points from their centroid.
double rmsSize(const Moments& m) { return std::sqrt(std::max(m.cov.trace(), 0.0)); }

void checkNotCoincident(ElementKind kind, const Axes& ax, std::size_t n) {
  if (std::sqrt(ax.value(2)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " " + name(kind) + " points coincide" +
         (isPlanar(kind) ? " in x, y" : "") + " (within " +
         num(kCoincidentMm) + " mm): probe points spread over the " + name(kind));
}

void checkNotCollinear(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                       const std::string& need, const std::string& fix) {
  if (std::sqrt(ax.value(1)) >= kRankTol * std::max(rmsSize(m), 1.0)) return;
  const double dev = maxDistanceFromLine(pts, m.centroid, ax.vec.col(2), isPlanar(kind));
  fail(name(kind) + " needs " + need + "; these " + std::to_string(pts.size()) +
       " lie within " + um(dev) + " of a line: " + fix);
}

void checkNotCoplanar(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                      const std::string& need, const std::string& fix) {
  if (std::sqrt(ax.value(0)) >= kRankTol * std::max(rmsSize(m), 1.0)) return;
  const double dev = maxDistanceFromPlane(pts, m.centroid, ax.vec.col(0));
  fail(name(kind) + " needs " + need + "; these " + std::to_string(pts.size()) +
       " lie within " + um(dev) + " of a plane: " + fix);
}

// ---------------------------------------------------------------------------------------
// Reduced least-squares problem and the Levenberg-Marquardt engine

template <int P>
struct Linearisation {
  Mat<P> R = Mat<P>::Zero();  // J = Q R, upper triangular
  Vec<P> qtr = Vec<P>::Zero();  // Q^T r
  double ssr = 0.0;
  bool ok = false;
};

// Turns rows (J_i, r_i) into R and Q^T r: Householder QR of [J r] (dense) or Cholesky of
// the blocked sums of [J r]^T [J r] (large n).
template <int P>
class Reducer {
 public:
  explicit Reducer(std::size_t n) : n_(n), dense_(n <= kDenseMax) {
    if (dense_) allocate();
  }
  bool dense() const { return dense_; }
  void makeDense() {
    dense_ = true;
    allocate();
  }
  void begin() {
    row_ = 0;
    in_block_ = 0;
    ssr_ = 0.0;
    block_ssr_ = 0.0;
    total_.setZero();
    block_.setZero();
  }
  void add(const Vec<P>& j, double r) {
    if (dense_) {
      a_.template block<1, P>(static_cast<Eigen::Index>(row_), 0) = j.transpose();
      a_(static_cast<Eigen::Index>(row_), P) = r;
      ++row_;
      block_ssr_ += r * r;
    } else {
      Vec<P + 1> v;
      v << j, r;
      for (int c = 0; c <= P; ++c)
        for (int k = 0; k <= c; ++k) block_(k, c) += v(k) * v(c);
    }
    if (++in_block_ == kBlock) flush();
  }
  Linearisation<P> finish() {
    flush();
    Linearisation<P> out;
    if (dense_) {
      qr_.compute(a_);
      const Mat<P + 1> ra =
          qr_.matrixQR().template topRows<P + 1>().template triangularView<Eigen::Upper>();
      out.R = ra.template topLeftCorner<P, P>();
      out.qtr = ra.col(P).template head<P>();
      out.ssr = ssr_;
    } else {
      const Mat<P> jtj = total_.template topLeftCorner<P, P>().template selfadjointView<Eigen::Upper>();
      Eigen::LLT<Mat<P>> llt(jtj);
      if (llt.info() != Eigen::Success) return out;
      out.R = llt.matrixU();
      out.qtr = llt.matrixL().solve(Vec<P>(total_.col(P).template head<P>()));
      out.ssr = total_(P, P);
    }
    out.ok = out.R.allFinite() && out.qtr.allFinite() && std::isfinite(out.ssr) &&
             (out.R.diagonal().array() != 0.0).all();
    return out;
  }

 private:
  void allocate() {
    // At least P + 1 rows so that the R factor of [J r] is square; extra rows are zero.
    a_.setZero(static_cast<Eigen::Index>(std::max<std::size_t>(n_, P + 1)), P + 1);
  }
  void flush() {
    ssr_ += block_ssr_;
    block_ssr_ = 0.0;
    total_ += block_;
    block_.setZero();
    in_block_ = 0;
  }
  std::size_t n_;
  bool dense_;
  std::size_t row_ = 0, in_block_ = 0;
  double ssr_ = 0.0, block_ssr_ = 0.0;
  Eigen::Matrix<double, Eigen::Dynamic, P + 1> a_;
  Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, P + 1>> qr_;
  Mat<P + 1> total_ = Mat<P + 1>::Zero(), block_ = Mat<P + 1>::Zero();
};

template <class Model>
Linearisation<Model::P> linearise(const Model& model, const typename Model::State& s,
                                  Reducer<Model::P>& red) {
  red.begin();
  model.rows(s, red);
  Linearisation<Model::P> l = red.finish();
  if (!l.ok && !red.dense()) {  // J^T J lost definiteness: redo on the full Jacobian
    red.makeDense();
    red.begin();
    model.rows(s, red);
    l = red.finish();
  }
  return l;
}

template <int P>
Vec<P> columnNorms(const Mat<P>& r) {
  return r.colwise().norm().transpose();
}

// argmin |R d + qtr|^2 + lambda |D d|^2.
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

template <class Model>
LmRun<Model> levenbergMarquardt(const Model& model, const typename Model::State& start,
                                int max_iterations, Reducer<Model::P>& red) {
  constexpr int P = Model::P;
  LmRun<Model> run;
  run.state = start;
  if (!model.valid(start)) return run;
  run.lin = linearise(model, start, red);
  if (!run.lin.ok) return run;
  Vec<P> scale = columnNorms(run.lin.R).cwiseMax(1e-300);
  double lambda = 0.0;
  double previous_size = std::numeric_limits<double>::infinity();
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
      if (std::isfinite(size)) {
        const typename Model::State next = model.apply(run.state, step);
        if (model.valid(next)) {
          const Linearisation<P> l = linearise(model, next, red);
          // Ties within the rounding of the sum of squares are accepted: close to the
          // solution a Gauss-Newton step changes the sum by less than its rounding error
          // and still moves the parameters by a meaningful amount. Each residual carries
          // a rounding error of about model.rounding (eps times the coordinates), so the
          // sum carries about 2 |r| sqrt(n) model.rounding.
          const double slack = kSsrSlack * run.lin.ssr +
                               2.0 * model.rounding * std::sqrt(model.count() * run.lin.ssr);
          if (l.ok && l.ssr <= run.lin.ssr + slack) {
            const bool gauss_newton = lambda == 0.0;
            const bool insignificant = run.lin.ssr - l.ssr <= slack;
            run.state = next;
            run.lin = l;
            scale = scale.cwiseMax(columnNorms(l.R));
            lambda = lambda < 1e-8 ? 0.0 : 0.1 * lambda;
            accepted = true;
            // Converged when the step is negligible, or when Gauss-Newton steps no longer
            // shrink while the sum of squares no longer changes: the rounding floor.
            if (size <= kStepTol || (gauss_newton && insignificant && size > 0.5 * previous_size))
              run.converged = true;
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

// Sum of squares of a model at a state (scoring of starts).
template <int P>
struct SsrSink {
  double ssr = 0.0;
  void add(const Vec<P>&, double r) { ssr += r * r; }
};

template <class Model>
double sumOfSquares(const Model& model, const typename Model::State& s) {
  SsrSink<Model::P> sink;
  model.rows(s, sink);
  return sink.ssr;
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
  const Eigen::MatrixXd scaled = l.R * norms.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeFullV);
  const double smax = svd.singularValues()(0);
  const double smin = svd.singularValues()(P - 1);
  c.condition = smin > 0.0 ? (smax / smin) * (smax / smin) : std::numeric_limits<double>::infinity();
  c.weakest = svd.matrixV().col(P - 1);
  return c;
}

// (J^T J)^-1 = R^-1 R^-T.
template <int P>
Mat<P> inverseNormal(const Linearisation<P>& l) {
  const Mat<P> rinv = l.R.template triangularView<Eigen::Upper>().solve(Mat<P>::Identity());
  return rinv * rinv.transpose();
}

// ---------------------------------------------------------------------------------------
// Models. Each provides rows(state, sink) -> sink.add(J_i, r_i) with r_i the signed
// orthogonal distance (as signedDistance) and J_i = d r_i / d(local parameters) at 0;
// apply(state, step) -> next state; stepSize(step) -> dimensionless size; valid(state).

// Circle in 2D on coordinates centred at the data centroid. Parameters: centre offsets
// (and the radius).
template <bool Fixed>
struct CircleModel {
  static constexpr int P = Fixed ? 2 : 3;
  struct State {
    Vector2d c = Vector2d::Zero();
    double r = 0.0;
  };
  const Points2* q;
  double size;
  double rounding;  // rounding error of one residual (mm)
  double count() const { return static_cast<double>(q->size()); }
  template <class Sink>
  void rows(const State& s, Sink& sink) const {
    Vec<P> j;
    for (const auto& p : *q) {
      const Vector2d v = p - s.c;
      const double rho = v.norm();
      if (rho > 0.0) {
        j(0) = -v.x() / rho;
        j(1) = -v.y() / rho;
      } else {
        j(0) = -1.0;
        j(1) = 0.0;
      }
      if constexpr (!Fixed) j(2) = -1.0;
      sink.add(j, rho - s.r);
    }
  }
  State apply(const State& s, const Vec<P>& d) const {
    State t = s;
    t.c += d.template head<2>();
    if constexpr (!Fixed) t.r += d(2);
    return t;
  }
  double stepSize(const Vec<P>& d) const { return d.cwiseAbs().maxCoeff() / size; }
  bool valid(const State& s) const { return s.c.allFinite() && std::isfinite(s.r) && s.r > 0.0; }
};

// Sphere on the original coordinates (the centre estimate is near the data, so p - c
// keeps its digits). Parameters: centre offsets (and the radius).
template <bool Fixed>
struct SphereModel {
  static constexpr int P = Fixed ? 3 : 4;
  struct State {
    Vector3d c = Vector3d::Zero();
    double r = 0.0;
  };
  const Points3* pts;
  double size;
  double rounding;
  double count() const { return static_cast<double>(pts->size()); }
  template <class Sink>
  void rows(const State& s, Sink& sink) const {
    Vec<P> j;
    for (const auto& p : *pts) {
      const Vector3d v = p - s.c;
      const double rho = v.norm();
      if (rho > 0.0) {
        j.template head<3>() = -v / rho;
      } else {
        j.template head<3>() = -Vector3d::UnitX();
      }
      if constexpr (!Fixed) j(3) = -1.0;
      sink.add(j, rho - s.r);
    }
  }
  State apply(const State& s, const Vec<P>& d) const {
    State t = s;
    t.c += d.template head<3>();
    if constexpr (!Fixed) t.r += d(3);
    return t;
  }
  double stepSize(const Vec<P>& d) const { return d.cwiseAbs().maxCoeff() / size; }
  bool valid(const State& s) const { return s.c.allFinite() && std::isfinite(s.r) && s.r > 0.0; }
};

// Axis state shared by cylinder and cone: axis point o (the foot of the data centroid),
// frame u (rows e1, e2, e3 = axis direction), radius at o, half angle (cone; may be
// negative while iterating: the axis then points toward decreasing radius).
struct AxisState {
  Vector3d o = Vector3d::Zero();
  Matrix3d u = Matrix3d::Identity();
  double r = 0.0;
  double psi = 0.0;
};

// Moves the axis point to the foot of `centroid`; for a cone the radius follows the taper.
AxisState recentred(const Vector3d& o, const Vector3d& dir, double r, double psi,
                    const Vector3d& centroid) {
  AxisState s;
  const double t = dir.dot(centroid - o);
  s.o = o + t * dir;
  s.u = frameOf(dir);
  s.r = r + t * std::tan(psi);
  s.psi = psi;
  return s;
}

// Local parameters (Forbes DITC 140/89 section 6): axis through (x0, y0, 0) of the frame,
// direction (a, b, 1) normalised, radius r (and half angle psi for the cone). In the frame,
// q = U (p - o), rho = |(q0, q1)|:
//   cylinder  d = rho - r,                    dd = [-q0/rho, -q1/rho, -q0 q2/rho, -q1 q2/rho, -1]
//   cone      d = (rho - r) cos psi - q2 sin psi
//             dd = [-q0 c/rho, -q1 c/rho, -q0 (q2 c/rho + s), -q1 (q2 c/rho + s), -c,
//                   -(rho - r) s - q2 c]   (c = cos psi, s = sin psi)
template <bool Fixed>
struct CylinderModel {
  static constexpr int P = Fixed ? 4 : 5;
  using State = AxisState;
  const Points3* pts;
  Vector3d centroid;
  double size;
  double rounding;
  double count() const { return static_cast<double>(pts->size()); }
  template <class Sink>
  void rows(const State& s, Sink& sink) const {
    Vec<P> j;
    for (const auto& p : *pts) {
      const Vector3d q = s.u * (p - s.o);
      double rho = std::sqrt(q.x() * q.x() + q.y() * q.y());
      const double rr = rho - s.r;
      if (!(rho > 0.0)) rho = std::numeric_limits<double>::min();
      const double cx = q.x() / rho, cy = q.y() / rho;
      j(0) = -cx;
      j(1) = -cy;
      j(2) = -cx * q.z();
      j(3) = -cy * q.z();
      if constexpr (!Fixed) j(4) = -1.0;
      sink.add(j, rr);
    }
  }
  State apply(const State& s, const Vec<P>& d) const {
    const Vector3d o = s.o + d(0) * s.u.row(0).transpose() + d(1) * s.u.row(1).transpose();
    const Vector3d dir = (s.u.row(2).transpose() + d(2) * s.u.row(0).transpose() +
                          d(3) * s.u.row(1).transpose())
                             .normalized();
    double r = s.r;
    if constexpr (!Fixed) r += d(4);
    return recentred(o, dir, r, 0.0, centroid);
  }
  double stepSize(const Vec<P>& d) const {
    double lengths = std::max(std::abs(d(0)), std::abs(d(1)));
    if constexpr (!Fixed) lengths = std::max(lengths, std::abs(d(4)));
    return std::max(lengths / size, std::max(std::abs(d(2)), std::abs(d(3))));
  }
  bool valid(const State& s) const { return s.o.allFinite() && s.u.allFinite() && s.r > 0.0; }
};

struct ConeModel {
  static constexpr int P = 6;
  using State = AxisState;
  const Points3* pts;
  Vector3d centroid;
  double size;
  double rounding;
  double count() const { return static_cast<double>(pts->size()); }
  template <class Sink>
  void rows(const State& s, Sink& sink) const {
    const double c = std::cos(s.psi), sn = std::sin(s.psi);
    Vec<P> j;
    for (const auto& p : *pts) {
      const Vector3d q = s.u * (p - s.o);
      double rho = std::sqrt(q.x() * q.x() + q.y() * q.y());
      const double rr = (rho - s.r) * c - q.z() * sn;
      const double dpsi = -(rho - s.r) * sn - q.z() * c;
      if (!(rho > 0.0)) rho = std::numeric_limits<double>::min();
      const double cx = q.x() / rho, cy = q.y() / rho;
      const double tilt = q.z() * c;
      j(0) = -cx * c;
      j(1) = -cy * c;
      j(2) = -(cx * tilt + q.x() * sn);
      j(3) = -(cy * tilt + q.y() * sn);
      j(4) = -c;
      j(5) = dpsi;
      sink.add(j, rr);
    }
  }
  State apply(const State& s, const Vec<P>& d) const {
    const Vector3d o = s.o + d(0) * s.u.row(0).transpose() + d(1) * s.u.row(1).transpose();
    const Vector3d dir = (s.u.row(2).transpose() + d(2) * s.u.row(0).transpose() +
                          d(3) * s.u.row(1).transpose())
                             .normalized();
    return recentred(o, dir, s.r + d(4), s.psi + d(5), centroid);
  }
  double stepSize(const Vec<P>& d) const {
    const double lengths = std::max({std::abs(d(0)), std::abs(d(1)), std::abs(d(4))});
    return std::max(lengths / size, std::max({std::abs(d(2)), std::abs(d(3)), std::abs(d(5))}));
  }
  bool valid(const State& s) const {
    return s.o.allFinite() && s.u.allFinite() && std::isfinite(s.r) &&
           std::abs(s.psi) < 0.5 * kPi - 1e-6;
  }
};

// ---------------------------------------------------------------------------------------
// Results

FitResult makeResult(const Element& e, const Points3& pts, int free_parameters,
                     std::vector<std::string> names, const Eigen::MatrixXd& cov, int iterations) {
  if (!e.position_mm.allFinite() || !e.direction.allFinite() || !std::isfinite(e.radius_mm) ||
      !std::isfinite(e.half_angle_rad))
    fail("least-squares " + name(e.kind) + " fit produced no finite element: the points do not "
         "determine a " + name(e.kind));
  FitResult out;
  out.element = e;
  out.method = FitMethod::LeastSquares;
  fillResiduals(out, pts, free_parameters);
  out.parameter_names = std::move(names);
  out.covariance_unscaled = cov;
  out.iterations = iterations;
  return out;
}

// ---------------------------------------------------------------------------------------
// Closed-form fits

FitResult fitLine2D(const Points3& pts, const Moments& m) {
  const std::size_t n = pts.size();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(m.cov.topLeftCorner<2, 2>());
  const Vector2d lam = es.eigenvalues().cwiseMax(0.0);
  if (std::sqrt(lam(1)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " line2d points coincide in x, y (within " +
         num(kCoincidentMm) + " mm): probe points spread along the line");
  if (lam(1) - lam(0) <= 1e-12 * lam(1))
    fail("line2d: the " + std::to_string(n) + " points spread equally in every direction, so no "
         "line is preferred: probe points along the line");
  Vector2d d = es.eigenvectors().col(1);
  d = canonical(Vector3d(d.x(), d.y(), 0.0)).head<2>();
  const Vector2d nrm(-d.y(), d.x());
  Element e;
  e.kind = ElementKind::Line2D;
  e.position_mm = Vector3d(m.centroid.x(), m.centroid.y(), 0.0);
  e.direction = Vector3d(d.x(), d.y(), 0.0);
  // Local parameters: offset t along the normal, rotation a (d' = d + a nrm). J_i = [-1,
  // -s_i] with s_i the coordinate along the line, so J^T J = diag(n, n var_along).
  const double dn = static_cast<double>(n);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(4, 2);
  g.block<2, 1>(0, 0) = nrm;
  g.block<2, 1>(2, 1) = nrm;
  const Eigen::Vector2d local(1.0 / dn, 1.0 / (dn * lam(1)));
  return makeResult(e, pts, 2, {"x_mm", "y_mm", "dx", "dy"},
                    g * local.asDiagonal() * g.transpose(), 0);
}

FitResult fitLine3D(const Points3& pts, const Moments& m, const Axes& ax) {
  const std::size_t n = pts.size();
  checkNotCoincident(ElementKind::Line3D, ax, n);
  if (ax.value(2) - ax.value(1) <= 1e-12 * ax.value(2))
    fail("line3d: the " + std::to_string(n) + " points spread equally in two directions, so no "
         "line is preferred: probe points along the line");
  Element e;
  e.kind = ElementKind::Line3D;
  e.position_mm = m.centroid;
  e.direction = canonical(ax.vec.col(2));
  // Local parameters: axis point offsets u, v along the other principal axes ea, eb and
  // tilts a, b toward them. The distance components are ea.q - u - a s, eb.q - v - b s, so
  // J^T J = diag(n, n, n var_along, n var_along).
  const double sign = e.direction.dot(ax.vec.col(2)) > 0 ? 1.0 : -1.0;
  const Vector3d ea = ax.vec.col(1), eb = ax.vec.col(0);
  const double dn = static_cast<double>(n);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6, 4);
  g.block<3, 1>(0, 0) = ea;
  g.block<3, 1>(0, 1) = eb;
  g.block<3, 1>(3, 2) = sign * ea;
  g.block<3, 1>(3, 3) = sign * eb;
  const Eigen::Vector4d local(1.0 / dn, 1.0 / dn, 1.0 / (dn * ax.value(2)),
                              1.0 / (dn * ax.value(2)));
  return makeResult(e, pts, 4, {"x_mm", "y_mm", "z_mm", "dx", "dy", "dz"},
                    g * local.asDiagonal() * g.transpose(), 0);
}

// Checks shared by the plane and the circle's plane.
void checkPlaneDetermined(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax) {
  const std::size_t n = pts.size();
  checkNotCoincident(kind, ax, n);
  checkNotCollinear(kind, pts, m, ax, ">= 3 non-collinear points", "add a point off that line");
  if (ax.value(1) - ax.value(0) <= 1e-12 * ax.value(2))
    fail(name(kind) + ": the " + std::to_string(n) + " points spread equally in two directions "
         "across a line, so no plane is preferred: probe points over a flat area");
}

// Plane local parameters: offset t along the normal n = e_min, tilts alpha, beta toward the
// principal axes e_max, e_mid. J_i = [-1, e_max.q, e_mid.q] and, the axes being principal,
// J^T J = diag(n, n var_max, n var_mid).
Eigen::Vector3d planeLocalCovariance(const Axes& ax, std::size_t n) {
  const double dn = static_cast<double>(n);
  return {1.0 / dn, 1.0 / (dn * ax.value(2)), 1.0 / (dn * ax.value(1))};
}

FitResult fitPlane(const Points3& pts, const Moments& m, const Axes& ax) {
  checkPlaneDetermined(ElementKind::Plane, pts, m, ax);
  Element e;
  e.kind = ElementKind::Plane;
  e.position_mm = m.centroid;  // the LS plane contains the centroid: it is its own foot
  e.direction = canonical(ax.vec.col(0));
  const double sign = e.direction.dot(ax.vec.col(0)) > 0 ? 1.0 : -1.0;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6, 3);
  g.block<3, 1>(0, 0) = ax.vec.col(0);
  g.block<3, 1>(3, 1) = sign * ax.vec.col(2);
  g.block<3, 1>(3, 2) = sign * ax.vec.col(1);
  const Eigen::Vector3d local = planeLocalCovariance(ax, pts.size());
  return makeResult(e, pts, 3, {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"},
                    g * local.asDiagonal() * g.transpose(), 0);
}

// ---------------------------------------------------------------------------------------
// Circle

struct CircleGuess {
  Vector2d c = Vector2d::Zero();
  double r = 0.0;
  bool ok = false;
};

// Taubin's algebraic circle fit, in Chernov's Newton form (Chernov 2010, section 5.10;
// MATLAB CircleFitByTaubin): moments of the centred, unit-scaled points, the smallest
// root of the characteristic cubic from 0 by Newton, then the centre.
CircleGuess taubin(const Points2& pts) {
  CircleGuess g;
  const std::size_t n = pts.size();
  Vector2d mean = Vector2d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(n);
  double spread = 0.0;
  for (const auto& p : pts) spread += (p - mean).squaredNorm();
  spread = std::sqrt(spread / static_cast<double>(n));
  if (!(spread > 0.0)) return g;
  double mxx = 0, myy = 0, mxy = 0, mxz = 0, myz = 0, mzz = 0;
  for (const auto& p : pts) {
    const double x = (p.x() - mean.x()) / spread, y = (p.y() - mean.y()) / spread;
    const double z = x * x + y * y;
    mxx += x * x, myy += y * y, mxy += x * y, mxz += x * z, myz += y * z, mzz += z * z;
  }
  const double dn = static_cast<double>(n);
  mxx /= dn, myy /= dn, mxy /= dn, mxz /= dn, myz /= dn, mzz /= dn;
  const double mz = mxx + myy;
  const double cov_xy = mxx * myy - mxy * mxy;
  const double var_z = mzz - mz * mz;
  const double a3 = 4.0 * mz;
  const double a2 = -3.0 * mz * mz - mzz;
  const double a1 = var_z * mz + 4.0 * cov_xy * mz - mxz * mxz - myz * myz;
  const double a0 = mxz * (mxz * myy - myz * mxy) + myz * (myz * mxx - mxz * mxy) - var_z * cov_xy;
  double x = 0.0, y = 1e20;
  for (int it = 0; it < 99; ++it) {
    const double yold = y;
    y = a0 + x * (a1 + x * (a2 + x * a3));
    if (std::abs(y) > std::abs(yold)) {
      x = 0.0;
      break;
    }
    const double dy = a1 + x * (2.0 * a2 + x * 3.0 * a3);
    const double xold = x;
    x = xold - y / dy;
    if (!std::isfinite(x) || x < 0.0) {
      x = 0.0;
      break;
    }
    if (std::abs(x - xold) <= 1e-12 * std::abs(x)) break;
  }
  const double det = x * x - x * mz + cov_xy;
  const Vector2d c(mxz * (myy - x) - myz * mxy, myz * (mxx - x) - mxz * mxy);
  const Vector2d centre = c / det / 2.0;
  if (!centre.allFinite() || det == 0.0) return g;
  g.c = mean + spread * centre;
  g.r = spread * std::sqrt(centre.squaredNorm() + mz);
  g.ok = std::isfinite(g.r) && g.r > 0.0;
  return g;
}

// A known radius R with points of mean squared distance s2 from their centroid m puts the
// centre at sqrt(R^2 - s2) from m (sum |p - c|^2 = n s2 + n |m - c|^2 on an exact circle);
// the side is taken from the free-radius start.
template <class V>
V knownRadiusCentre(const V& mean, double s2, const V& free_centre, double radius, const V& side) {
  V u = free_centre - mean;
  if (!(u.norm() > 0.0)) u = side;
  return mean + u.normalized() * std::sqrt(std::max(radius * radius - s2, 0.0));
}

struct CircleSolution {
  Vector2d c;
  double r;
  int iterations;
  Eigen::MatrixXd cov;  // x, y (, r)
};

std::string arcAdvice(const Points2& q, const Vector2d& c) {
  std::vector<double> ang;
  ang.reserve(q.size());
  for (const auto& p : q) ang.push_back(std::atan2(p.y() - c.y(), p.x() - c.x()));
  return "the " + degrees(angularSpan(std::move(ang))) +
         " arc is too short to determine a radius: spread the points over a longer arc or give "
         "the known radius";
}

template <bool Fixed>
CircleSolution solveCircleWith(ElementKind kind, const Points2& q, const CircleGuess& start,
                               double size, int max_iterations) {
  const double eps = std::numeric_limits<double>::epsilon();
  CircleModel<Fixed> model{&q, size, 8.0 * eps * (size + start.r)};
  typename CircleModel<Fixed>::State s{start.c, start.r};
  Reducer<CircleModel<Fixed>::P> red(q.size());
  const auto run = levenbergMarquardt(model, s, max_iterations, red);
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition)) {
    if (Fixed)
      fail(name(kind) + ": the centre is not determined by these points with the known radius: "
           "spread the points around the circle");
    fail(name(kind) + ": " + arcAdvice(q, run.state.c));
  }
  if (!run.converged)
    fail("least-squares " + name(kind) + " did not converge in " +
         std::to_string(max_iterations) + " iterations: raise max_iterations or check that the "
         "points outline one circle");
  return {run.state.c, run.state.r, run.iterations, inverseNormal(run.lin)};
}

// 2D circle LS on coordinates centred at their centroid (q has zero mean).
CircleSolution solveCircle(ElementKind kind, const Points2& q, const Vector2d& minor_axis,
                           const LeastSquaresOptions& o) {
  double s2 = 0.0;
  for (const auto& p : q) s2 += p.squaredNorm();
  s2 /= static_cast<double>(q.size());
  const double size = std::sqrt(s2);
  CircleGuess g = taubin(q);
  if (!g.ok) fail(name(kind) + ": the points lie on a straight line: " +
                  "spread them over a longer arc or give the known radius");
  if (o.fixed_radius_mm) {
    g.c = knownRadiusCentre<Vector2d>(Vector2d::Zero(), s2, g.c, *o.fixed_radius_mm, minor_axis);
    g.r = *o.fixed_radius_mm;
    return solveCircleWith<true>(kind, q, g, size, o.max_iterations);
  }
  return solveCircleWith<false>(kind, q, g, size, o.max_iterations);
}

FitResult fitCircle2D(const Points3& pts, const Moments& m, const LeastSquaresOptions& o) {
  const std::size_t n = pts.size();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(m.cov.topLeftCorner<2, 2>());
  const Vector2d lam = es.eigenvalues().cwiseMax(0.0);
  if (std::sqrt(lam(1)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " circle2d points coincide in x, y (within " +
         num(kCoincidentMm) + " mm): probe points spread around the circle");
  if (std::sqrt(lam(0)) < kRankTol * std::max(std::sqrt(lam(0) + lam(1)), 1.0)) {
    const Vector2d d = es.eigenvectors().col(1);
    const double dev = maxDistanceFromLine(pts, m.centroid, Vector3d(d.x(), d.y(), 0.0), true);
    fail("circle2d needs >= 3 non-collinear points; these " + std::to_string(n) + " lie within " +
         um(dev) + " of a line: spread the points around the circle");
  }
  Points2 q(n);
  for (std::size_t i = 0; i < n; ++i) q[i] = (pts[i] - m.centroid).head<2>();
  const CircleSolution c = solveCircle(ElementKind::Circle2D, q, es.eigenvectors().col(0), o);
  Element e;
  e.kind = ElementKind::Circle2D;
  e.position_mm = Vector3d(m.centroid.x() + c.c.x(), m.centroid.y() + c.c.y(), 0.0);
  e.radius_mm = o.fixed_radius_mm ? *o.fixed_radius_mm : c.r;
  std::vector<std::string> names{"x_mm", "y_mm"};
  if (!o.fixed_radius_mm) names.push_back("r_mm");
  return makeResult(e, pts, o.fixed_radius_mm ? 2 : 3, names, c.cov, c.iterations);
}

FitResult fitCircle3D(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkPlaneDetermined(ElementKind::Circle3D, pts, m, ax);
  const std::size_t n = pts.size();
  // In-plane coordinates along the principal axes e1 = e_max, e2 = e_mid; the plane's
  // local parameters (t, alpha, beta) are defined along the same axes.
  const Vector3d nrm = ax.vec.col(0), e1 = ax.vec.col(2), e2 = ax.vec.col(1);
  Points2 q(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3d v = pts[i] - m.centroid;
    q[i] = Vector2d(e1.dot(v), e2.dot(v));
  }
  const CircleSolution c = solveCircle(ElementKind::Circle3D, q, Vector2d(0.0, 1.0), o);
  Element e;
  e.kind = ElementKind::Circle3D;
  e.position_mm = m.centroid + c.c.x() * e1 + c.c.y() * e2;
  e.direction = canonical(nrm);
  e.radius_mm = o.fixed_radius_mm ? *o.fixed_radius_mm : c.r;
  const double sign = e.direction.dot(nrm) > 0 ? 1.0 : -1.0;
  // Local parameters [t, alpha, beta | cx, cy (, r)], the plane and circle blocks
  // independent to first order (a tilt moves the projections by tilt x out-of-plane
  // deviation). Centre = centroid + t n + cx e1' + cy e2' with e1' = e1 - alpha n,
  // e2' = e2 - beta n.
  const bool fixed = o.fixed_radius_mm.has_value();
  const int pc = fixed ? 2 : 3;
  Eigen::MatrixXd local = Eigen::MatrixXd::Zero(3 + pc, 3 + pc);
  local.topLeftCorner<3, 3>() = planeLocalCovariance(ax, n).asDiagonal();
  local.bottomRightCorner(pc, pc) = c.cov;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6 + (fixed ? 0 : 1), 3 + pc);
  g.block<3, 1>(0, 0) = nrm;
  g.block<3, 1>(0, 1) = -c.c.x() * nrm;
  g.block<3, 1>(0, 2) = -c.c.y() * nrm;
  g.block<3, 1>(0, 3) = e1;
  g.block<3, 1>(0, 4) = e2;
  g.block<3, 1>(3, 1) = sign * e1;
  g.block<3, 1>(3, 2) = sign * e2;
  if (!fixed) g(6, 5) = 1.0;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
  if (!fixed) names.push_back("r_mm");
  // The residuals are radial deviations in the plane: only the in-plane centre and the
  // radius move them to first order, hence 3 (2) free parameters for the dof.
  return makeResult(e, pts, pc, names, g * local * g.transpose(), c.iterations);
}

// ---------------------------------------------------------------------------------------
// Sphere

struct SphereGuess {
  Vector3d c = Vector3d::Zero();
  double r = 0.0;
  bool ok = false;
};

// Kasa: |q|^2 = 2 c.q + k, linear in (c, k), on coordinates centred at the centroid and
// scaled by the RMS size (Forbes DITC 140/89 section 5: the linear sphere start).
SphereGuess kasaSphere(const Points3& pts, const Moments& m) {
  const double size = rmsSize(m);
  Mat<4> a = Mat<4>::Zero();
  Vec<4> b = Vec<4>::Zero();
  for (const auto& p : pts) {
    const Vector3d q = (p - m.centroid) / size;
    const Vec<4> v(2.0 * q.x(), 2.0 * q.y(), 2.0 * q.z(), 1.0);
    a.selfadjointView<Eigen::Upper>().rankUpdate(v);
    b += v * q.squaredNorm();
  }
  const Vec<4> x = Mat<4>(a.selfadjointView<Eigen::Upper>()).colPivHouseholderQr().solve(b);
  SphereGuess g;
  g.c = m.centroid + size * x.head<3>();
  g.r = size * std::sqrt(x(3) + x.head<3>().squaredNorm());
  g.ok = g.c.allFinite() && std::isfinite(g.r) && g.r > 0.0;
  return g;
}

std::string capAdvice(const Points3& pts, const Vector3d& c) {
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : pts) mean += (p - c).normalized();
  double half = 0.0;
  if (mean.norm() > 0.0) {
    mean.normalize();
    for (const auto& p : pts) {
      const Vector3d u = (p - c).normalized();
      half = std::max(half, std::atan2(u.cross(mean).norm(), u.dot(mean)));
    }
  }
  return "the points cover a spherical cap of only " + degrees(2.0 * half) +
         " (seen from the centre), too small to determine a radius: spread the points wider or "
         "give the known radius";
}

template <bool Fixed>
FitResult fitSphereWith(const Points3& pts, const Moments& m, const Axes& ax,
                        const LeastSquaresOptions& o) {
  using Model = SphereModel<Fixed>;
  const double eps = std::numeric_limits<double>::epsilon();
  const double rounding = 8.0 * eps * (m.centroid.cwiseAbs().maxCoeff() + 2.0 * rmsSize(m));
  Model model{&pts, rmsSize(m), rounding};
  Reducer<Model::P> red(pts.size());
  auto fromGuess = [&](SphereGuess g) {
    if (Fixed) {
      g.c = knownRadiusCentre<Vector3d>(m.centroid, m.cov.trace(), g.c, *o.fixed_radius_mm,
                                        ax.vec.col(0));
      g.r = *o.fixed_radius_mm;
    }
    return typename Model::State{g.c, g.r};
  };
  LmRun<Model> run;
  bool have = false;
  if (o.start && o.start->kind == ElementKind::Sphere && o.start->position_mm.allFinite() &&
      o.start->radius_mm > 0.0) {
    run = levenbergMarquardt(model, fromGuess({o.start->position_mm, o.start->radius_mm, true}),
                             o.max_iterations, red);
    have = run.converged && run.lin.ok;
  }
  if (!have) {
    const SphereGuess g = kasaSphere(pts, m);
    if (!g.ok)
      fail("sphere: the algebraic start is undefined, the points do not outline a sphere: "
           "probe points spread over the sphere");
    run = levenbergMarquardt(model, fromGuess(g), o.max_iterations, red);
  }
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition)) {
    if (Fixed)
      fail("sphere: the centre is not determined by these points with the known radius: "
           "spread the points over the sphere");
    fail("sphere: " + capAdvice(pts, run.state.c));
  }
  if (!run.converged)
    fail("least-squares sphere did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations or check that the points outline one sphere");
  Element e;
  e.kind = ElementKind::Sphere;
  e.position_mm = run.state.c;
  e.radius_mm = Fixed ? *o.fixed_radius_mm : run.state.r;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm"};
  if (!Fixed) names.push_back("r_mm");
  return makeResult(e, pts, Model::P, names, inverseNormal(run.lin), run.iterations);
}

FitResult fitSphereLs(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkNotCoplanar(ElementKind::Sphere, pts, m, ax, ">= 4 non-coplanar points",
                   "add a point off that plane (e.g. at the pole)");
  return o.fixed_radius_mm ? fitSphereWith<true>(pts, m, ax, o)
                           : fitSphereWith<false>(pts, m, ax, o);
}

// ---------------------------------------------------------------------------------------
// Cylinder and cone

// Algebraic start for a given axis direction: in the frame of `dir` through the centroid,
// x^2 + y^2 = A x + B y + K (cylinder: a circle in projection, Kasa) or
// x^2 + y^2 = A x + B y + K + M z + N z^2 (cone: rho(z)^2 = (r0 + t z)^2 about the axis
// through (A/2, B/2)), linear in the unknowns; scaled coordinates.
std::optional<AxisState> algebraicAxis(const Points3& pts, const Vector3d& centroid, double size,
                                       const Vector3d& dir, bool cone,
                                       const std::optional<double>& fixed) {
  const Matrix3d u = frameOf(dir);
  Mat<5> a = Mat<5>::Zero();
  Vec<5> b = Vec<5>::Zero();
  double s2 = 0.0;
  for (const auto& p : pts) {
    const Vector3d q = u * (p - centroid) / size;
    const double w = q.x() * q.x() + q.y() * q.y();
    const Vec<5> v(q.x(), q.y(), 1.0, q.z(), q.z() * q.z());
    a.selfadjointView<Eigen::Upper>().rankUpdate(v);
    b += v * w;
    s2 += w;
  }
  s2 /= static_cast<double>(pts.size());
  const int k = cone ? 5 : 3;
  const Eigen::MatrixXd full = Mat<5>(a.selfadjointView<Eigen::Upper>());
  const Eigen::VectorXd x = full.topLeftCorner(k, k).colPivHouseholderQr().solve(b.head(k));
  if (!x.allFinite()) return std::nullopt;
  Vector2d c(0.5 * x(0), 0.5 * x(1));
  const double r2 = x(2) + c.squaredNorm();
  if (!(r2 > 0.0)) return std::nullopt;
  double r = std::sqrt(r2);
  const double t = cone ? x(3) / (2.0 * r) : 0.0;
  c *= size;
  r *= size;
  if (fixed) {
    c = knownRadiusCentre<Vector2d>(Vector2d::Zero(), s2 * size * size, c, *fixed,
                                    Vector2d::UnitX());
    r = *fixed;
  }
  AxisState s;
  s.u = u;
  s.o = centroid + u.transpose() * Vector3d(c.x(), c.y(), 0.0);
  s.r = r;
  s.psi = std::atan(t);
  if (!s.o.allFinite() || !std::isfinite(s.r) || !std::isfinite(s.psi)) return std::nullopt;
  return s;
}

// Start from options.start: the axis of a cylinder, cone, line3d or circle3d; its radius
// (and half angle) when the kinds match, otherwise the algebraic ones for that axis.
std::optional<AxisState> userAxisStart(const LeastSquaresOptions& o, const Points3& pts,
                                       const Moments& m, bool cone) {
  if (!o.start) return std::nullopt;
  const Element& s = *o.start;
  if (s.kind != ElementKind::Cylinder && s.kind != ElementKind::Cone &&
      s.kind != ElementKind::Line3D && s.kind != ElementKind::Circle3D)
    return std::nullopt;
  if (!s.position_mm.allFinite() || !s.direction.allFinite() || !(s.direction.norm() > 0.0))
    return std::nullopt;
  const Vector3d dir = s.direction.normalized();
  if (cone && s.kind == ElementKind::Cone && s.radius_mm > 0.0 && s.half_angle_rad > 0.0 &&
      s.half_angle_rad < 0.5 * kPi)
    return recentred(s.position_mm, dir, s.radius_mm, s.half_angle_rad, m.centroid);
  if (!cone && (s.kind == ElementKind::Cylinder || s.kind == ElementKind::Circle3D) &&
      (o.fixed_radius_mm || s.radius_mm > 0.0))
    return recentred(s.position_mm, dir, o.fixed_radius_mm ? *o.fixed_radius_mm : s.radius_mm,
                     0.0, m.centroid);
  return algebraicAxis(pts, m.centroid, rmsSize(m), dir, cone, o.fixed_radius_mm);
}

// Candidate axis directions: the principal axes, and the best of a hemisphere grid
// (Fibonacci lattice, ~11 deg apart) scored by the geometric sum of squares of the
// algebraic start for each direction.
template <class Model>
std::vector<Vector3d> candidateAxes(const Model& model, const Points3& sample, const Moments& m,
                                    const Axes& ax, bool cone, const std::optional<double>& fixed) {
  std::vector<Vector3d> dirs{ax.vec.col(2), ax.vec.col(1), ax.vec.col(0)};
  constexpr int kGrid = 160;
  constexpr int kKeep = 3;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  std::vector<std::pair<double, Vector3d>> scored;
  for (int k = 0; k < kGrid; ++k) {
    const double z = (k + 0.5) / kGrid;
    const double rxy = std::sqrt(1.0 - z * z);
    const Vector3d d(rxy * std::cos(golden * k), rxy * std::sin(golden * k), z);
    const auto s = algebraicAxis(sample, m.centroid, rmsSize(m), d, cone, fixed);
    if (!s || !model.valid(*s)) continue;
    const double ssr = sumOfSquares(model, *s);
    if (std::isfinite(ssr)) scored.emplace_back(ssr, d);
  }
  std::sort(scored.begin(), scored.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  int kept = 0;
  for (const auto& [ssr, d] : scored) {
    bool distinct = true;
    for (std::size_t i = 3; i < dirs.size(); ++i)
      distinct = distinct && std::abs(d.dot(dirs[i])) < std::cos(0.3);
    if (!distinct) continue;
    dirs.push_back(d);
    if (++kept == kKeep) break;
  }
  return dirs;
}

// Same axis element (orientation, axis position, radius, half angle) within 1e-6.
bool sameAxisElement(const AxisState& a, const AxisState& b, double size) {
  const Vector3d da = a.u.row(2).transpose(), db = b.u.row(2).transpose();
  const double dot = da.dot(db);
  const Vector3d off = b.o - a.o;
  return std::abs(dot) >= 1.0 - 1e-12 && (off - da * da.dot(off)).norm() <= 1e-6 * size &&
         std::abs(a.r - b.r) <= 1e-6 * size &&
         std::abs(a.psi - std::copysign(1.0, dot) * b.psi) <= 1e-6;
}

// The lowest sum of squares. When several starts reach different solutions with the same
// sum of squares to rounding (typically exact fits through as many points as parameters,
// e.g. NIST's 6-point cone, which two cones interpolate), the solution reached from most
// starts, i.e. with the largest basin of attraction, is reported.
template <class Model>
LmRun<Model> pickSolution(const std::vector<LmRun<Model>>& runs, std::size_t n, double size) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& r : runs) lowest = std::min(lowest, r.lin.ssr);
  const double noise = static_cast<double>(n) * (1e-10 * size) * (1e-10 * size);
  const double tie = std::max(lowest * (1.0 + 1e-9), noise);
  std::size_t best = 0;
  int best_votes = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].lin.ssr > tie) continue;
    int votes = 0;
    for (const auto& r : runs)
      if (r.lin.ssr <= tie && sameAxisElement(runs[i].state, r.state, size)) ++votes;
    if (votes > best_votes || (votes == best_votes && runs[i].lin.ssr < runs[best].lin.ssr)) {
      best = i;
      best_votes = votes;
    }
  }
  return runs[best];
}

template <class Model>
LmRun<Model> fitAxisElement(const Points3& pts, const Moments& m, const Axes& ax,
                            const LeastSquaresOptions& o, bool cone) {
  const double size = rmsSize(m);
  const double rounding = 8.0 * std::numeric_limits<double>::epsilon() *
                          (m.centroid.cwiseAbs().maxCoeff() + 2.0 * size);
  const Model full{&pts, m.centroid, size, rounding};
  Reducer<Model::P> red(pts.size());
  if (const auto start = userAxisStart(o, pts, m, cone)) {
    auto run = levenbergMarquardt(full, *start, o.max_iterations, red);
    if (run.converged && run.lin.ok) return run;
  }
  // Starts are compared on a subsample of large sets; the winner is polished on all points.
  Points3 sample;
  const bool subsampled = pts.size() > kStartSample;
  if (subsampled) {
    sample.reserve(kStartSample);
    for (std::size_t i = 0; i < kStartSample; ++i) sample.push_back(pts[i * pts.size() / kStartSample]);
  }
  const Points3& sp = subsampled ? sample : pts;
  const Model sub{&sp, m.centroid, size, rounding};
  Reducer<Model::P> sub_red(sp.size());
  const int sub_iterations = subsampled ? std::min(o.max_iterations, 50) : o.max_iterations;
  std::vector<LmRun<Model>> runs;
  for (const Vector3d& d : candidateAxes(sub, sp, m, ax, cone, o.fixed_radius_mm)) {
    const auto start = algebraicAxis(sp, m.centroid, size, d, cone, o.fixed_radius_mm);
    if (!start) continue;
    auto run = levenbergMarquardt(sub, *start, sub_iterations, sub_red);
    if (run.lin.ok) runs.push_back(run);
  }
  if (runs.empty()) return LmRun<Model>{};
  const LmRun<Model> best = pickSolution(runs, sp.size(), size);
  if (!subsampled) return best;
  return levenbergMarquardt(full, best.state, o.max_iterations, red);
}

// Why an axis fit is ill-determined: along-axis extent or angular sector of the points.
template <int P>
std::string axisAdvice(ElementKind kind, const Points3& pts, const AxisState& s,
                       const Conditioning<P>& cond, bool fixed) {
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  std::vector<double> ang;
  ang.reserve(pts.size());
  for (const auto& p : pts) {
    const Vector3d q = s.u * (p - s.o);
    zmin = std::min(zmin, q.z());
    zmax = std::max(zmax, q.z());
    ang.push_back(std::atan2(q.y(), q.x()));
  }
  double axial = cond.weakest(2) * cond.weakest(2) + cond.weakest(3) * cond.weakest(3);
  if (kind == ElementKind::Cone) axial += cond.weakest(5) * cond.weakest(5);
  if (axial > 0.5)
    return name(kind) + ": the points span only " + num(zmax - zmin) + " mm along the axis, too "
           "little to fix its direction: probe at two or more levels further apart";
  return name(kind) + ": the " + degrees(angularSpan(std::move(ang))) + " sector is too narrow "
         "to determine the radius: probe further around the " + name(kind) +
         (kind == ElementKind::Cylinder && !fixed ? " or give the known radius" : "");
}

// Propagation of the local covariance to the reported axis parameters. With w = centroid -
// o (w1, w2 in the frame) the reported point (foot of the centroid on the moved axis) is
// o + x0 e1 + y0 e2 + (a w1 + b w2) e3 to first order; the direction moves by a e1 + b e2
// (times the sign flip to the reported direction).
Eigen::MatrixXd axisJacobian(const AxisState& s, const Vector3d& centroid, double sign,
                             int rows, int cols) {
  const Vector3d e1 = s.u.row(0).transpose(), e2 = s.u.row(1).transpose(),
                 e3 = s.u.row(2).transpose();
  const Vector3d w = centroid - s.o;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(rows, cols);
  g.block<3, 1>(0, 0) = e1;
  g.block<3, 1>(0, 1) = e2;
  g.block<3, 1>(0, 2) = e1.dot(w) * e3;
  g.block<3, 1>(0, 3) = e2.dot(w) * e3;
  g.block<3, 1>(3, 2) = sign * e1;
  g.block<3, 1>(3, 3) = sign * e2;
  return g;
}

template <bool Fixed>
FitResult fitCylinderWith(const Points3& pts, const Moments& m, const Axes& ax,
                          const LeastSquaresOptions& o) {
  using Model = CylinderModel<Fixed>;
  const auto run = fitAxisElement<Model>(pts, m, ax, o, false);
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition))
    fail(axisAdvice(ElementKind::Cylinder, pts, run.state, cond, Fixed));
  if (!run.converged)
    fail("least-squares cylinder did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations, give a start (options.start) or check that the "
         "points outline one cylinder");
  const AxisState& s = run.state;
  const Vector3d e3 = s.u.row(2).transpose();
  Element e;
  e.kind = ElementKind::Cylinder;
  e.direction = canonical(e3);
  e.position_mm = s.o + e3 * e3.dot(m.centroid - s.o);
  e.radius_mm = Fixed ? *o.fixed_radius_mm : s.r;
  const double sign = e.direction.dot(e3) > 0 ? 1.0 : -1.0;
  Eigen::MatrixXd g = axisJacobian(s, m.centroid, sign, Fixed ? 6 : 7, Model::P);
  if (!Fixed) g(6, 4) = 1.0;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
  if (!Fixed) names.push_back("r_mm");
  return makeResult(e, pts, Model::P, names, g * inverseNormal(run.lin) * g.transpose(),
                    run.iterations);
}

FitResult fitCylinder(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkNotCollinear(ElementKind::Cylinder, pts, m, ax, "points around its axis",
                    "probe at several angles around the cylinder");
  checkNotCoplanar(ElementKind::Cylinder, pts, m, ax, "points off a single plane",
                   "probe at two or more levels along the axis and around it");
  return o.fixed_radius_mm ? fitCylinderWith<true>(pts, m, ax, o)
                           : fitCylinderWith<false>(pts, m, ax, o);
}

FitResult fitCone(const Points3& pts, const Moments& m, const Axes& ax,
                  const LeastSquaresOptions& o) {
  checkNotCollinear(ElementKind::Cone, pts, m, ax, "points around its axis",
                    "probe at several angles around the cone");
  checkNotCoplanar(ElementKind::Cone, pts, m, ax, "points off a single plane",
                   "probe at two or more levels along the axis and around it");
  const auto run = fitAxisElement<ConeModel>(pts, m, ax, o, true);
  const auto cond = conditioning(run.lin);
  if (run.lin.ok && std::abs(run.state.psi) < kMinHalfAngle)
    fail("cone: the fitted half angle is " + num(std::abs(run.state.psi)) +
         " rad, i.e. the apex angle is 0: these points lie on a cylinder; fit a cylinder instead");
  if (!run.lin.ok || !(cond.condition <= kMaxCondition))
    fail(axisAdvice(ElementKind::Cone, pts, run.state, cond, false));
  if (!run.converged)
    fail("least-squares cone did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations, give a start (options.start) or check that the "
         "points outline one cone");
  const AxisState& s = run.state;
  if (!(s.r > 0.0))
    fail("cone: the fitted apex lies among the points (radius " + num(s.r) +
         " mm at their centroid): measure one side of the apex only");
  const Vector3d e3 = s.u.row(2).transpose();
  // The reported direction points toward increasing radius.
  const double sign = s.psi > 0.0 ? 1.0 : -1.0;
  Element e;
  e.kind = ElementKind::Cone;
  e.direction = sign * e3;
  e.position_mm = s.o + e3 * e3.dot(m.centroid - s.o);
  e.radius_mm = s.r;
  e.half_angle_rad = std::abs(s.psi);
  Eigen::MatrixXd g = axisJacobian(s, m.centroid, sign, 8, 6);
  // Radius at the moved foot point: r + (a w1 + b w2) tan(psi); half angle flips with the sign.
  const Vector3d w = m.centroid - s.o;
  g(6, 2) = s.u.row(0).dot(w) * std::tan(s.psi);
  g(6, 3) = s.u.row(1).dot(w) * std::tan(s.psi);
  g(6, 4) = 1.0;
  g(7, 5) = sign;
  return makeResult(e, pts, 6, {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz", "r_mm", "half_angle_rad"},
                    g * inverseNormal(run.lin) * g.transpose(), run.iterations);
}

}  // namespace

FitResult fitLeastSquares(ElementKind kind, const Points3& points, const LeastSquaresOptions& options) {
  checkOptions(kind, options);
  checkCount(kind, points);
  const Moments m = computeMoments(kind, points);
  const Axes ax = principalAxes(m);
  checkNotCoincident(kind, ax, points.size());
  checkDuplicates(kind, points, m);
  switch (kind) {
    case ElementKind::Line2D: return fitLine2D(points, m);
    case ElementKind::Line3D: return fitLine3D(points, m, ax);
    case ElementKind::Plane: return fitPlane(points, m, ax);
    case ElementKind::Circle2D: return fitCircle2D(points, m, options);
    case ElementKind::Circle3D: return fitCircle3D(points, m, ax, options);
    case ElementKind::Sphere: return fitSphereLs(points, m, ax, options);
    case ElementKind::Cylinder: return fitCylinder(points, m, ax, options);
    case ElementKind::Cone: return fitCone(points, m, ax, options);
  }
  fail("least-squares fit of an unknown element kind");
}

}  // namespace probeloop::geometry
