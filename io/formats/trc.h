#pragma once
// Motion Analysis TRC marker files (text, tab separated).
//
// Layout read and written:
//   line 1  PathFileType <tab> 4 <tab> (X/Y/Z) <tab> <file name>
//   line 2  header keys:   DataRate CameraRate NumFrames NumMarkers Units OrigDataRate
//                          OrigDataStartFrame OrigNumFrames (any order, any subset)
//   line 3  header values, one per key
//   line 4  Frame# <tab> Time <tab> name1 <tab><tab> name2 ...   (a name every 3rd column)
//   line 5  <tab><tab> X1 Y1 Z1 X2 Y2 Z2 ...
//   (blank line, optional)
//   data    frame <tab> time <tab> x1 y1 z1 x2 ...
//
// Quirks handled by ReadTrc (each oddity becomes a warning in
// take.provenance.warnings unless stated otherwise):
// - Empty cells are missing samples (NaN). "NaN"/"nan" cells also mean missing.
//   A marker with only some of its three cells filled is missing in that frame
//   (warned once with a count).
// - Rows may be shorter than the header (trailing cells omitted) or end with a
//   trailing tab; CRLF or LF line ends; a line with no tab is split on spaces.
// - The number of markers is taken from the data: the largest of the names on
//   line 4 and the cells used by any row. NumMarkers in the header is only
//   compared (BTK Gait.trc says 66, names 33 markers and fills 105). Markers
//   without a name get "unnamed_<column>" (1-based marker column); NumMarkers=0
//   files with no names (BTK 10002-*.trc) therefore read as unnamed markers.
// - Names are trimmed of surrounding spaces (BTK Knee.trc " genou1_NewMarker3 ").
//   A duplicated name gets a suffix "_2", "_3", ... (warned).
// - Names written one per column instead of every third column are accepted.
// - NumFrames differing from the rows present (e.g. a truncated file) is warned;
//   the rows present are returned. Non-consecutive frame numbers are warned.
// - Units "mm", "cm", "m", "in", ... are converted to millimetres; an unknown or
//   absent unit is warned and read as millimetres. take.source_units keeps the
//   unit string of the file.
// - DataRate missing or invalid: CameraRate is used (warned).
// Errors (csw::ParseError naming the file and line): empty file, not a TRC file,
// header cut before the names line (BTK Truncated.trc), rate missing or outside
// [1e-6, 1e7] Hz, a frame number or coordinate that is not a number, a frame
// number beyond +-2^50, an infinite or absurdly large (> 1e12 mm) coordinate,
// or a table whose implied size (frames x markers) is far larger than the file
// could hold (more than 8 cells per byte).
// Missing file: csw::IoError.
#include <string>

#include "core/take.h"

namespace csw {

// Reads a TRC file: markers in millimetres (converted from the header's Units),
// rate_hz = DataRate, first_frame = frame number of the first data row,
// name = file stem, provenance.sources = {path, sha256, "trc"}, warnings in
// take.provenance.warnings.
Take ReadTrc(const std::string& path);

// Writes take.markers as a TRC file in millimetres with DataRate = CameraRate =
// OrigDataRate = take.rate_hz, frame numbers from take.first_frame, times
// (frame index / rate), missing samples as empty cells and coordinates in the
// shortest text that reads back to the same float (exact round trip). Tabs and
// line breaks in marker names are replaced by spaces. Throws InvalidInput for a
// take without a positive rate or with names not matching the marker count,
// IoError when the file cannot be written.
void WriteTrc(const std::string& path, const Take& take);

}  // namespace csw
