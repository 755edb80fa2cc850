// What a CMM exchange document holds, independent of its format (QIF 3.0 now, DMIS next): the
// features of a test piece with their nominal or measured geometry and their points, and named
// derived values (characteristics). The planner fills one as a plan, the simulated CMM and the
// evaluation as results; the readers of other software's files return one.
//
// Conventions: lengths in mm in the document's frame (the part frame for our test pieces);
// a point's normal points away from the material (QIF's MeasurePoint/Normal, our
// cmm_points.csv nx,ny,nz), so a probe approaches along -normal; directions are unit vectors.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <vector>

namespace probeloop::interop {

// The kinds we write; a reader also reports the others it meets (Other, with the format's name).
enum class CmmFeatureKind { Plane, Sphere, Cylinder, Circle, Point, Line, Other };
const char* cmmFeatureKindName(CmmFeatureKind k);  // plane, sphere, cylinder, circle, point, line, other

struct CmmPoint {
  Eigen::Vector3d p_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero: not given
};

// Plane: a point on it and its outward normal; sphere, circle: the centre (circle: the normal
// of its plane); cylinder: a point on the axis and the axis; point: the point; line: a point
// and its direction.
struct CmmGeometry {
  bool given = false;
  Eigen::Vector3d location_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double diameter_mm = NAN;  // sphere, cylinder, circle
  double form_mm = NAN;      // measured form, when known
  // The fitting algorithm the file states for it (QIF SubstituteFeatureAlgorithmEnum, e.g.
  // LEASTSQUARES, MINMAX; "OTHER: <text>" for OtherSubstituteFeatureAlgorithm); "" not stated.
  std::string algorithm;
};

struct CmmFeature {
  std::string name;  // our feature id (the manifest's); a reader: the file's feature name
  CmmFeatureKind kind = CmmFeatureKind::Plane;
  std::string kind_name;  // the format's own name (e.g. QIF "OppositeParallelLines"), for Other
  bool internal = false;  // sphere, cylinder, circle: a bore (material outside)
  CmmGeometry nominal;    // a plan's, and the Features section of results
  CmmGeometry measured;   // results
  std::vector<CmmPoint> points;  // planned (a plan) or measured (results)
  // Reading only: where the feature stands in the file, and which measurement run it is in.
  int line = 0;
  int run = 0;
};

// A derived value (e.g. EX0C), a length in mm or an angle in rad, with its combined standard
// uncertainty (NaN: none).
struct CmmCharacteristic {
  std::string name;
  bool angular = false;
  double value = 0, u = NAN;
};

// A program's move (DMIS GOTO, or PTMEAS: the probing move to its point), in order.
struct CmmMove {
  int line = 0;
  Eigen::Vector3d to_mm = Eigen::Vector3d::Zero();
  bool probing = false;
};

// Reading: a producer's mistake that keeps the meaning (element order, a dangling or
// self-referencing id, an unknown extension, a missing optional block), read anyway: the line it
// stands on and what was done (docs/interop.md#lenient-reading).
struct CmmWarning {
  int line = 0;
  std::string what;
};

// How a reader treats those mistakes: strict refuses them (InputError at the same line, with
// the same words), as every reader did before issue 34.
struct CmmReadOptions {
  bool strict = false;
};

struct CmmDocument {
  std::string file;       // reading: the path, for messages
  std::string part_name;  // writing: in the DMIS program's title and the content hash of the QIF QPId
  std::vector<CmmFeature> features;
  std::vector<CmmCharacteristic> characteristics;
  std::vector<CmmMove> moves;  // reading a program: its moves (DMIS), for a collision check
  // Reading: the file's own length unit and what was passed over (one line each).
  std::string length_unit = "mm";
  int runs = 0;
  std::vector<std::string> notes;
  std::vector<CmmWarning> warnings;
  // Reading results: every measured point set in the file and its points, assigned to a feature
  // or not (QIF MeasuredPointSets; DMIS: the features' points).
  int point_sets = 0;
  std::size_t point_set_points = 0;
};

// "FILE:LINE: warning: WHAT", as the CLI prints each warning (stderr, or a read's text output).
std::string cmmWarningText(const CmmDocument& d, const CmmWarning& w);

}  // namespace probeloop::interop
