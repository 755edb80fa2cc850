// The stock as it is being cut by flat end mills, in the part frame (docs/simulator.md §2.4).
//
// Two representations of the same material:
// - a height field (Z-map, cells of `cell_mm`) for what a move removes (volume, where) and
//   for collision checks: coarse, fast. A cell holds the top of the material in its column
//   (-inf: none); a cell belongs to the blank when its centre does;
// - the exact surface: the blank (a box, or the vertical cylinder inscribed in the box's XY
//   extent) minus the holes minus the union of the swept volumes of every cut. A flat end
//   mill of radius r moving on a horizontal segment sweeps {xy within r of the segment,
//   z >= bottom} (a plunge: a cylinder); on a horizontal arc of radius rho about a centre it
//   sweeps {xy within r of the arc, z >= bottom}: the annulus sector plus the two end disks
//   (plus the disk of radius r - rho about the centre when rho < r). A line query returns
//   where the line first enters material, exact to floating point, so CMM and probe points
//   see micrometre-level cut errors.
//
// Contract:
// - holes are removed before any cut, exactly; in the height field only a hole that reaches
//   the top of the blank changes a column (the height field holds the top of the material,
//   so a blind hole from below does not show in it);
// - recordCut() records one swept volume per horizontal or vertical segment; a ramp (XY and
//   Z together) is split into horizontal pieces, each at its upper Z: n = ceil(|dz| / 1e-5 mm)
//   pieces (so the floor of each piece lies within 0.01 um of the ramp), at most one per
//   0.05 mm of length (a steep ramp), at least one;
// - recordArc() splits an arc into pieces of at most 90 deg (each wedge convex, so a line
//   meets each piece's annulus sector in at most two intervals); an arc of more than one
//   turn sweeps one turn;
// - a swept volume that cannot reach the blank (outside its XY footprint, or above its top)
//   is not stored: it removes nothing, and queries stay fast when a program moves in the air;
// - every swept volume carries a tag (the caller's cut number); firstMaterialHit says which
//   one bounds the material where a line enters it (-1: the blank's own surface or a hole).
// Lengths in mm, angles in rad, volumes in mm^3.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <optional>
#include <vector>

namespace probeloop::sim {

struct SweptCut {
  Eigen::Vector3d p0, p1;  // tool-bottom centre at the start and end, part frame
  double radius = 0;
  double time_s = 0;
  int tag = -1;
  Eigen::Vector2d lo, hi;  // XY bounding box of the swept region (for quick rejection)
};

// One piece (<= 90 deg) of a swept arc: angles lo < hi counterclockwise from +X about centre.
struct SweptArc {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double rho = 0, radius = 0;  // path radius, tool radius
  double lo_rad = 0, hi_rad = 0;
  double z_bottom = 0;
  double time_s = 0;
  int tag = -1;
  Eigen::Vector2d lo, hi;  // XY bounding box of the swept region
};

// An arc from start_rad by sweep_rad (positive counterclockwise) as the counterclockwise
// [lo, lo + span] it covers, span at most one turn (a longer sweep covers one turn).
struct CcwArc {
  double lo = 0, span = 0;
};
CcwArc ccwArc(double start_rad, double sweep_rad);

struct Removal {
  double volume_mm3 = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // of the removed material
  double mean_radius_mm = 0;  // arcs: volume-weighted mean distance of the removed material from the centre
};

class Stock {
 public:
  Stock() = default;
  // A box, or with `cylindrical` the vertical cylinder inscribed in the box's XY extent.
  Stock(const Eigen::Vector3d& min_mm, const Eigen::Vector3d& max_mm, double cell_mm = 0.25, bool cylindrical = false);

  // Material absent from the start (a drilled hole): a vertical cylinder.
  void addHole(const Eigen::Vector2d& centre_mm, double radius_mm, double z_min_mm, double z_max_mm);

  // Can a flat end mill of this radius on the segment p0-p1 reach the blank at all (the XY
  // box of its swept region, its lowest bottom)? False: removeHeightField removes nothing and
  // recordCut stores nothing, so a move in the air (the chords of a ring around the part)
  // may skip both.
  bool segmentReachesBlank(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius) const;
  // The height field part: what the move from p0 to p1 removes (undisplaced tool path).
  Removal removeHeightField(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius);
  // The same for a horizontal arc (tool-bottom centre at z_bottom on a circle of radius rho
  // about centre, from angle start_rad by sweep_rad, positive counterclockwise).
  Removal removeHeightFieldArc(const Eigen::Vector2d& centre, double rho, double start_rad, double sweep_rad,
                               double z_bottom, double radius);
  // The exact part: the swept volume of the real (displaced) tool path. False when nothing
  // was stored (the swept volume cannot reach the blank).
  bool recordCut(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius, double time_s, int tag = -1);
  bool recordArc(const Eigen::Vector2d& centre, double rho, double start_rad, double sweep_rad, double z_bottom,
                 double radius, double time_s, int tag = -1);

  // Highest material under a disk (cells whose centres lie within `radius` of xy) per the
  // height field; -inf if none.
  double topUnder(const Eigen::Vector2d& xy, double radius) const;
  // The largest distance from `axis` of material whose top lies above `above_z` (height
  // field, to the far corner of each cell); -inf if none. The cells are sorted by their
  // distance from the axis once, and a query walks them from the outside in to the first
  // with material above z: a program that turns the table a thousand times, with the tool's
  // z drifting thermally, pays little. An axis that differs from the sorted one by d (a
  // part's thermal expansion moves it by micrometres) adds d: an upper bound, never less.
  double maxMaterialRadius(const Eigen::Vector2d& axis, double above_z) const;

  // First s in [0, max_s] where from + s dir enters material (exact surface); nullopt if none.
  std::optional<double> firstMaterial(const Eigen::Vector3d& from, const Eigen::Vector3d& dir, double max_s) const;
  struct Hit {
    double s = 0;
    int tag = -1;  // the swept volume that bounds the material there; -1 = the blank or a hole
  };
  std::optional<Hit> firstMaterialHit(const Eigen::Vector3d& from, const Eigen::Vector3d& dir, double max_s) const;

  const Eigen::Vector3d& min() const { return min_; }
  const Eigen::Vector3d& max() const { return max_; }
  bool cylindrical() const { return cylindrical_; }
  std::size_t sweptVolumes() const { return cuts_.size() + arcs_.size(); }

 private:
  Eigen::Vector3d min_ = Eigen::Vector3d::Zero(), max_ = Eigen::Vector3d::Zero();
  bool cylindrical_ = false;
  Eigen::Vector2d centre_ = Eigen::Vector2d::Zero();  // of the cylindrical blank
  double blank_radius_ = 0;
  double cx_ = 0.25, cy_ = 0.25;
  int nx_ = 0, ny_ = 0;
  int cellX(double x) const;
  int cellY(double y) const;
  bool reachesBlank(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double z_bottom) const;
  std::vector<double> top_;
  struct Hole {
    Eigen::Vector2d centre;
    double radius, z_min, z_max;
  };
  std::vector<Hole> holes_;
  std::vector<SweptCut> cuts_;
  std::vector<SweptArc> arcs_;
  struct RadiusOrder {
    bool ready = false;
    Eigen::Vector2d axis = Eigen::Vector2d::Zero();
    std::vector<std::uint32_t> cells;  // farthest from the axis first
    std::vector<double> radius;        // their distances (cell centre + half diagonal)
    std::size_t first = 0;             // cells before it have no material left
  };
  mutable RadiusOrder radius_order_;
};

}  // namespace probeloop::sim
