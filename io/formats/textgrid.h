#pragma once
// Praat TextGrid files (text formats; the binary format is refused).
//
// Reading follows Praat's own rule for text files: the file is a sequence of
// numbers, "strings" and <flags>; anything else (the "xmin =", "item [1]:",
// "intervals: size =" labels of the long format) is skipped. So one reader takes
//   - the long ("ooTextFile") and short ("ooTextFile short", or the bare-value
//     layout praatio writes) formats,
//   - ELAN-exported TextGrids ("item[1]:", "intervals [1]" without a colon,
//     "xmin = 0.0"), labels glued to values ("size=3", "text=\"a\""),
//   - UTF-8 (with or without BOM), UTF-16 LE/BE (with BOM, or detected from a
//     zero byte in the first code unit), Latin-1 bytes that are not valid UTF-8,
//   - CRLF or LF line ends; "!" starts a comment running to the end of the line,
//   - strings with doubled quotes ("" stands for one ") and line breaks inside
//     (a CRLF or lone CR inside a string is read as LF),
//   - interval tiers ("IntervalTier") and point tiers ("TextTier"),
//   - "<absent>" tiers (a TextGrid with no tiers), gaps between intervals,
//   - negative zero (-0), read as 0.
// Errors (csw::ParseError naming the file and line): not a Praat text file, a
// binary or non-TextGrid object, a value of the wrong kind or not a number,
// NaN/inf (also as the words nan/inf), xmin > xmax (of the grid, a tier or an interval), a count that is
// negative, not an integer or larger than the rest of the file could hold, an
// unknown tier class, or the end of the file before the declared content.
// Missing file: csw::IoError. Anything after the declared tiers is ignored.
//
// Labels: intervals keep start_s <= end_s; point-tier
// labels have start_s == end_s == the point's time. Each tier's start_s/end_s
// is the tier's own xmin/xmax.
#include <string>
#include <vector>

#include "core/take.h"

namespace csw {

// Reads all tiers of a TextGrid; the grid's xmin/xmax go to *xmin / *xmax.
std::vector<LabelTier> ReadTextGrid(const std::string& path, double* xmin = nullptr, double* xmax = nullptr);

// Writes a TextGrid in UTF-8 (no BOM), Praat's long text format by default or
// the short format. Numbers are written in the shortest text that reads back to
// the same double, so write -> read is exact. Labels are written as they are,
// gaps included (Praat reads such files but edits them oddly; use
// FillIntervalGaps first for tiers that must cover their domain, e.g. tiers read
// from an EAF). A tier whose start_s and end_s are both 0 while it holds labels
// gets the grid's xmin/xmax.
// Throws InvalidInput for non-finite times, xmin > xmax or a label with
// start > end, IoError when the file cannot be written.
void WriteTextGrid(const std::string& path, const std::vector<LabelTier>& tiers, double xmin, double xmax,
                   bool short_format = false);

// An interval tier made contiguous as Praat and praatio expect: an empty-text
// interval is inserted in every gap before, between and after the labels within
// [tier.start_s, tier.end_s] (labels assumed in time order; overlaps are left
// as they are). Point tiers are returned unchanged.
LabelTier FillIntervalGaps(const LabelTier& tier);

}  // namespace csw
