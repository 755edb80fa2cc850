// QIF 3.0 (ANSI/DMSC QIF 3.0, ISO 23952:2020) plans and results, written and read with libxml2
// (docs/interop.md has the subset, element by element).
//
// Writing: qifPlan makes a QIF Plan document: Features (a definition, a nominal with its
// geometry and a PointList, and an item per feature; the planned points as NominalPointSets of
// MeasurePoint, point + outward normal) and an ordered Plan measuring every feature in turn.
// qifResults makes a QIF Results document: the same Features (without planned points), the
// Characteristics of the derived values (UserDefinedLinear/AngularCharacteristic, value and
// combinedUncertainty), and one MeasurementResults with each feature's measurement (geometry
// when has_geometry) and its MeasuredPointSet (points, normals when given, compensated). Kinds
// written: plane, sphere, cylinder (others are refused with a logic_error: our planner makes
// no others). Both validate against the QIF 3.0.0 XSD (tests with xmllint). Deterministic: the
// QPId is a UUID made from a hash of the content; numbers in fixed notation (xs:decimal takes no
// exponent), lengths to 1 nm, directions to 1e-9, characteristics to 1e-9 mm / 1e-12 rad.
//
// Reading: readQifResults parses a QIF 3 document (any producer, default namespace or a
// prefix; no network) and returns every measured feature of every MeasurementResults with its
// kind, name (the measurement's FeatureName, else its item's, else its nominal's), geometry
// and points (Whole/Range/SinglePointSetId into MeasuredPointSets), in mm (FileUnits'
// primary linear unit by name or its UnitConversion factor; a linearUnit attribute on an
// element by the declared units). A document with no FileUnits is read in mm, with a note.
// Characteristic measurements with a Value are returned by their item's name.
// Contract: InputError with file:line for what is not QIF 3 (another root, namespace or
// versionQIF), a point set whose Points do not hold 3 x count numbers (of a set a feature
// reads), a number that does not parse, an unknown length unit; binary point sets
// (BinaryPoints) are refused with the reason. Nothing is guessed silently: what is passed over
// is listed in notes, what is read despite a producer's mistake in warnings.
// Lenient (docs/interop.md#lenient-reading): what a producer got wrong without changing the
// meaning is read with a warning in the document's warnings (its line, what was done):
// elements out of the XSD's order (MeasurementResults, feature measurements), a PointList id
// that names no MeasuredPointSet (dangling, or the measurement's own id: the only unreferenced
// set on the feature's measured geometry is assigned, else the points stay unassigned), a
// feature measurement without PointList whose unreferenced set lies on its geometry
// (assigned), elements in another namespace (passed over). options.strict refuses each of
// them instead (InputError at the same line). Every MeasuredPointSet is counted
// (point_sets, point_set_points), referenced or not.
#pragma once
#include <string>

#include "interop/cmm_document.hpp"

namespace probeloop::interop {

std::string qifPlan(const CmmDocument& plan);
std::string qifResults(const CmmDocument& results);

CmmDocument readQifResults(const std::string& path, const CmmReadOptions& options = {});
// A QIF plan's features (nominal geometry, internal/external from the definition) with their
// planned points (NominalPointSets' MeasurePoints, by the nominal's PointList); the name is the
// nominal's Name, else its item's FeatureName, else empty. InputError as above, and for a
// plan without feature nominals.
CmmDocument readQifPlan(const std::string& path);
CmmDocument parseQifPlan(const std::string& text, const std::string& file_name);
CmmDocument parseQifResults(const std::string& text, const std::string& file_name, const CmmReadOptions& options = {});

// True when a text looks like a QIF document (an XML root QIFDocument), for format detection.
bool looksLikeQif(const std::string& text);

}  // namespace probeloop::interop
