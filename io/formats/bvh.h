#pragma once
// Biovision Hierarchy (BVH) skeleton captures: read into a Take (joint
// positions as markers, global joint orientations, the skeleton) and written
// back from one (docs/bvh.md).
//
// Layout read and written:
//   HIERARCHY
//   ROOT <name> { OFFSET x y z  CHANNELS n <channel>...  (JOINT <name> {...} | End Site {...})... }
//   (more ROOTs may follow)
//   MOTION
//   Frames: <n>
//   Frame Time: <seconds>
//   <n rows of as many numbers as the CHANNELS counts add up to>
//
// Conventions (those of the Biovision format as Blender, MotionBuilder and
// fairmotion read it):
// - A joint's channels are any of Xposition Yposition Zposition Xrotation
//   Yrotation Zrotation, each at most once, in any order, 0 to 6 of them.
// - Rotations are in degrees. The local rotation is the product of the axis
//   rotations in the order the channels are listed (intrinsic): "Zrotation
//   Xrotation Yrotation" is R = Rz(z)·Rx(x)·Ry(y). The global orientation of a
//   joint is parent_global · R (a root's parent is the lab frame).
// - Position channels give the joint's translation from its parent, in the
//   parent's axes, and REPLACE the OFFSET's components they name (the OFFSET
//   is the rest pose); a joint's translation is applied before its rotation,
//   whatever the order of its channels. position = parent_position +
//   parent_global · translation.
// - An End Site takes its parent's orientation; its position is parent_position
//   + parent_global · OFFSET. It becomes a marker named "<parent name>_End"
//   (after the parent's name is made unique).
// - Joint j of Take::skeleton is marker j (parents before children, in file
//   order, end sites included); positions are in millimetres (file units ×
//   the scale), orientations unit quaternions (w, x, y, z) with w >= 0.
//
// Quirks accepted: CRLF, LF, CR and mixed line ends; tabs; leading and trailing
// whitespace; blank lines anywhere; '{' and '}' on the line of the keyword or
// their own; "Frames:"/"Frame Time:" with or without spaces around ':';
// numbers like ".0083333", "-0.000000", "1e-3"; joint names with spaces (the
// words on the line of ROOT/JOINT up to '{', joined by one space); duplicate
// names (suffixed "_2", "_3", ..., warned).
// Errors (csw::ParseError naming the file and line): empty file, no HIERARCHY,
// unbalanced braces, a keyword out of place, a missing OFFSET, more than 6 or
// repeated or unknown channel names, CHANNELS in an End Site, nesting deeper
// than kBvhMaxDepth or more than kBvhMaxJoints joints, no MOTION, a Frames count
// that is not an integer or more than the rest of the file can hold, a Frame
// Time that is not a number in [1e-7, 1e6] s, a motion row with the wrong
// number of values, a value that is not a finite number (NaN, inf) or out of
// range (|position| > 1e12 mm), fewer rows than Frames (truncated) or more.
// Missing file: csw::IoError.
#include <string>
#include <string_view>
#include <vector>

#include "core/take.h"

namespace csw {

inline constexpr int kBvhMaxDepth = 256;       // nesting of joints
inline constexpr int kBvhMaxJoints = 1 << 16;  // joints + end sites

struct BvhReadOptions {
  // Length unit of the file: "mm", "cm", "dm", "m" or "in"; "" guesses it
  // from the skeleton's size (GuessBvhUnits) and adds a warning saying what
  // was guessed.
  std::string units;
};

// True for the units BVH files are read and written in: mm, cm, dm, m, in.
bool IsBvhUnit(const std::string& units);

// What GuessBvhUnits concluded.
struct BvhUnitGuess {
  std::string units;         // "mm", "cm", "dm", "m" or "in"
  double mm_per_unit = 1.0;  // 1, 10, 100, 1000 or 25.4
  double size = 0.0;         // the skeleton's size the guess rests on, in file units
};

// The size of a skeleton: the largest extent along x, y or z of its rest pose
// (joints placed by their offsets, all rotations zero), in the offsets' units.
// For a standing person in a T-pose this is the height (or the arm span).
double SkeletonRestSize(const std::vector<SkeletonJoint>& skeleton);

// Guesses the length unit from a skeleton's size in file units, taking it for
// a person about 1.7 m tall: m below 5.4 (about 1.7), dm below 33.7 (about 17:
// MakeHuman exports decimetres), in below 107 (about 67), cm below 537 (about
// 170), mm above (about 1700); the bounds are the geometric means of
// neighbouring heights.
BvhUnitGuess GuessBvhUnits(double size);

// Reads a BVH file: markers = joint positions (mm), orientations, skeleton
// (offsets in mm), rate_hz = 1 / Frame Time, first_frame = 1, name = file stem,
// source_units = the unit used, provenance.sources = {path, sha256, "bvh"},
// warnings in take.provenance.warnings. Throws InvalidInput for an unknown
// options.units.
Take ReadBvh(const std::string& path, const BvhReadOptions& options = {});

// Same, from the text of a file (path names it in errors; no provenance source).
Take ParseBvh(std::string_view text, const std::string& path, const BvhReadOptions& options = {});

struct BvhWriteOptions {
  // Length unit written: "mm", "cm", "dm", "m" or "in"; "" = take.source_units when
  // it is one of these, else "mm".
  std::string units;
};

// The BVH text of a take with a skeleton: the hierarchy from take.skeleton
// (offsets converted to the unit), Frame Time = 1 / rate_hz, and per frame
// each joint's channels from the take: position channels from the markers
// (the root's position; other joints' translation from their parent, in the
// parent's axes), rotation channels as the Euler angles, in the joint's
// channel order, of local = parent_global⁻¹ · global (orientations).
// Positions are written as the shortest text of their float value, angles in
// degrees with 6 decimals. Throws InvalidInput when the take has no skeleton,
// no positive rate, markers/orientations/names that do not match the
// skeleton, a malformed skeleton (a parent after its child, channels on an
// end site, unknown channels), or a missing (NaN) position or orientation a
// channel needs (naming frame and joint).
std::string FormatBvh(const Take& take, const BvhWriteOptions& options = {});

// FormatBvh written to path (IoError when it cannot be written).
void WriteBvh(const std::string& path, const Take& take, const BvhWriteOptions& options = {});

// How far WriteBvh's output will place joints from take.markers: the largest
// distance (mm) over frames between a joint's stored position and the one its
// parent's position and orientation and its OFFSET give (joints without
// position channels, end sites included; NaN samples skipped). Up to float
// rounding (about 1e-3 mm) 0 for a take read by ReadBvh; a take built by hand
// (a virtual signer) whose bones do not keep the skeleton's lengths, or whose
// orientations do not turn the bones where the markers are, gives more.
// Throws InvalidInput when markers, orientations and skeleton do not match.
double SkeletonPositionMismatchMm(const Take& take);

// Euler angles (radians) a, b, c about the axes axes[0], axes[1], axes[2]
// (0 = x, 1 = y, 2 = z, all different) with R = R_a(a)·R_b(b)·R_c(c) for the
// unit quaternion (w, x, y, z). The middle angle is in [-pi/2, pi/2]; at gimbal
// lock the last angle is 0.
void QuaternionToEuler(const double q_wxyz[4], const int axes[3], double angles[3]);

}  // namespace csw
