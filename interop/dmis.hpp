// DMIS (ANSI/DMIS 105.2, ISO 22093) programs and output files, the subset docs/interop.md
// lists: what a CMM point plan needs and what CMM packages report.
//
// Writing: dmisProgram makes a .dmi: DMISMN, UNITS/MM,ANGDEC, MODE/PROG,MAN, per feature its
// nominal F(id)=FEAT/PLANE|CYLNDR|SPHERE, then MEAS/<type>,F(id),n with a GOTO to the clearance
// height above each point's approach start (5 mm along its outward normal), a GOTO down to it,
// PTMEAS/CART,x,y,z,i,j,k (the nominal surface point; ijk its outward normal, as most producers
// write it: the probe travels along -ijk), the GOTO back up, ENDMES; OUTPUT/FA(id) per feature;
// ENDFIL. Every move is vertical or at the clearance height (20 mm above the highest point), so
// a plan whose points are reachable from above (our test pieces) never moves through the part;
// no alignment or sensor statements (site-specific; a $$ line says so). dmisOutput makes a .dmo
// as the simulated CMM reports: FILNAM, UNITS, per feature its measured points as
// FA(<id>_P<nn>)=FEAT/POINT,CART,x,y,z,i,j,k, its nominal F(id) and its actual FA(id) when it has
// measured geometry, ENDFIL. Labels are upper case, at most 16 characters ([A-Z][A-Z0-9_]*); a
// longer or other id is a logic_error (ours are 2-8). Numbers fixed, 6 decimals (mm: 1 nm;
// vectors as cmm_points.csv writes them); lines over 80 characters are continued after a comma
// with '$'.
//
// Reading: parseDmisProgram reads the F(..)=FEAT nominals, each MEAS block's PTMEAS points (the
// simulated CMM measures them) and the moves (GOTO, and PTMEAS as the probing move) in order. parseDmisOutput reads the FA(..)=FEAT actuals: a FEAT/POINT
// actual labelled <feature>_P<nn>, where the file also has a feature <feature>, is a point of that
// feature; any other actual is a feature with its measured geometry (a lone FEAT/POINT a point
// feature). Both accept any case, blanks, CRLF, '$$' comments, '$' continuations, UNITS/INCH
// (converted to mm), and vectors given as direction angles in degrees (a component beyond 1, as
// GEOPAK writes them). FEAT types other than POINT, PLANE, CYLNDR, SPHERE and CIRCLE, and what
// they do not read (tolerances, datums, OUTPUT, GOTO, sensor and report statements), are skipped
// and counted in one note per keyword. InputError with file:line for a statement that does not
// parse, a number that is not one, a MEAS block whose PTMEAS count differs from its n, a PTMEAS
// outside a MEAS block, a MEAS of a feature not defined before it, a label reused for another
// kind of feature.
#pragma once
#include <string>

#include "interop/cmm_document.hpp"

namespace probeloop::interop {

std::string dmisProgram(const CmmDocument& plan, const std::string& title);
std::string dmisOutput(const CmmDocument& results, const std::string& title);

// Lenient (docs/interop.md#lenient-reading), both readers: a file without ENDFIL (perhaps cut
// short: what is there is read), statements after ENDFIL (passed over), and a label defined or
// reported again (the later one read: F(X) twice in a program or an output, FA(X) twice in an
// output) are warnings with their line. A program's MEAS block without its ENDMES is closed at
// the next MEAS, ENDFIL or the end of the file when its PTMEAS count is its n (a count that does
// not add up stays refused), and an ENDMES without MEAS is passed over. options.strict refuses
// each at the same line, with the warning's first words.
CmmDocument parseDmisProgram(const std::string& text, const std::string& file_name, const CmmReadOptions& options = {});
CmmDocument parseDmisOutput(const std::string& text, const std::string& file_name, const CmmReadOptions& options = {});

// A DMIS text: its first statement (after comments) is DMISMN or FILNAM (DMISMD); a program
// when it is DMISMN or DMISMD.
bool looksLikeDmis(const std::string& text);
bool isDmisProgram(const std::string& text);

}  // namespace probeloop::interop
