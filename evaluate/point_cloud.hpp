// Reading a point cloud for a single-feature fit (`probeloop fit`): CSV, NIST .ds, XYZ
// and PLY.
//
// Contract:
// - csv: a header row; coordinates from columns x_mm,y_mm,z_mm (or x,y,z); optional unit
//   approach directions nx,ny,nz (the canonical points CSV of docs/architecture.md#data-contracts qualifies; its
//   other columns are ignored). A file with a `feature` or `cycle` column holding more than
//   one value (a campaign's points) must be narrowed by the selection: otherwise an error
//   lists the values and names --feature / --cycle.
// - ds: NIST algorithm-testing format, first line N, then N lines "x y z".
// - xyz: one point per line, >= 3 numbers separated by blanks or commas, '#' comments;
//   extra columns are ignored.
// - ply: ascii, binary_little_endian or binary_big_endian; the vertex element's x, y, z
//   properties of any scalar type; other elements and properties are skipped.
// - qif, dmis: a QIF 3.0 Results document or a DMIS output file (interop/): the measured points
//   of the feature --feature names (required when more than one feature has points; an error
//   lists them; a DMIS label in any case, as DMIS labels are case-insensitive). The reader's warnings (lenient reading, docs/interop.md#lenient-reading) are
//   returned in warnings, "file:line: what was wrong; what was done"; select.strict refuses them.
// - auto: by extension (.csv, .ds, .xyz/.txt/.asc, .ply, .qif, .dmo).
// - Every bad line is an InputError with file:line and what was expected; NaN and inf are
//   refused. An empty cloud is an error.
#pragma once
#include <string>
#include <vector>

#include "geometry/elements.hpp"

namespace probeloop::evaluate {

struct PointCloud {
  std::string file;
  std::string format;                  // csv, ds, xyz, ply
  geometry::Points3 points_mm;
  geometry::Points3 approach;          // empty unless the file carries nx,ny,nz (csv)
  std::vector<int> source_lines;       // 1-based line of each point (ply binary: 0; qif/dmis: the feature's)
  std::vector<std::string> warnings;   // qif/dmis: what the lenient reader warned about
};

// Rows of a points CSV to fit: the `feature` and `cycle` columns' values (empty: not selected).
struct PointSelection {
  std::string feature;
  std::string cycle;
  bool strict = false;  // qif/dmis: refuse what the lenient reader would warn about
};

PointCloud readPointCloud(const std::string& path, const std::string& format = "auto",
                          const PointSelection& select = {});
// qif, dmis: fills pc.points_mm, source_lines and warnings (point_cloud_cmm.cpp).
void readCmmExchange(PointCloud& pc, const std::string& text, const PointSelection& select);

}  // namespace probeloop::evaluate
