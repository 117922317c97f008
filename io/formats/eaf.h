#pragma once
// ELAN annotation files (.eaf, EAF 2.7 / 2.8 / 3.0 and compatible), read and
// written with pugixml.
//
// Reading:
// - TIME_ORDER slots are in milliseconds and become seconds. Slots without a
//   TIME_VALUE (unaligned, typical of Time_Subdivision tiers) are placed
//   evenly between the nearest aligned slots of the same tier's chain of
//   annotations, as ELAN displays them.
// - Time-aligned tiers (ALIGNABLE_ANNOTATION) become interval tiers with one
//   label per annotation, sorted by start time (Included_In tiers may keep gaps;
//   overlaps are kept as they are).
// - Reference tiers (REF_ANNOTATION: Symbolic_Association and
//   Symbolic_Subdivision, possibly stacked) are aligned to the annotation they
//   refer to: an annotation alone under its parent takes the parent's interval;
//   n annotations under one parent (ordered by PREVIOUS_ANNOTATION) share it in
//   n equal parts. An annotation that cannot be aligned (unknown parent,
//   reference cycle, no aligned slot to interpolate from) is skipped with a
//   warning; a tier none of whose annotations could be aligned is skipped with a
//   warning. Tiers without annotations are returned empty.
// - A tier whose annotations all have zero duration is returned as a point tier
//   (that is how WriteEaf stores point tiers).
// - Every tier's domain is [0, the largest time in the document].
// - TIME_UNITS other than milliseconds is warned (values are read as ms).
//   Duplicate TIER_IDs are warned and both tiers returned; duplicate slot or
//   annotation ids are warned and the first definition is used.
// Errors (csw::ParseError naming the file, byte offset and line): malformed XML,
// a root other than ANNOTATION_DOCUMENT, a TIME_VALUE that is not a finite
// non-negative number, an ALIGNABLE_ANNOTATION referring to an unknown slot,
// or one whose start is after its end. Missing file: csw::IoError.
//
// Writing (EAF 3.0, UTF-8): one top-level time-aligned tier per LabelTier with
// the linguistic type "default-lt"; times rounded to whole milliseconds;
// adjacent labels of a tier share their time slot; labels with empty text are
// not written (ELAN shows gaps instead); point-tier labels become zero-duration
// annotations; an empty tier name becomes "tier <n>" (1-based position) and
// duplicate names get " (2)", " (3)", ... (TIER_ID must be non-empty and
// unique). media_url, when given, is written as the MEDIA_DESCRIPTOR (a path
// without a scheme is turned into a file:// URL; the MIME type follows the
// extension). Throws InvalidInput for negative or non-finite times, IoError
// when the file cannot be written.
#include <string>
#include <vector>

#include "core/take.h"

namespace csw {

std::vector<LabelTier> ReadEaf(const std::string& path, std::vector<std::string>* warnings = nullptr);

void WriteEaf(const std::string& path, const std::vector<LabelTier>& tiers, const std::string& media_url = "");

}  // namespace csw
