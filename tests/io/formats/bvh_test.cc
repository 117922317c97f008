// BVH reader/writer: hand-written fixtures whose forward kinematics are worked
// out by hand, quirks of real exporters, read -> write -> read round trips,
// hostile inputs and the third-party exports of ../shared/data/bvh checked
// against their REFERENCE.tsv.
#include "io/formats/bvh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "tests/io/formats/test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

using testing::ExpectParseError;
using testing::SharedData;
using testing::TempDir;
using testing::WriteBytes;

constexpr double kPi = 3.14159265358979323846;

bool HasWarning(const Take& take, const std::string& needle) {
  for (const std::string& w : take.provenance.warnings) {
    if (w.find(needle) != std::string::npos) return true;
  }
  return false;
}

void ExpectPosition(const Take& take, int64_t frame, int64_t joint, double x, double y, double z, double tol = 1e-4) {
  const float* p = take.markers.at(frame, joint);
  EXPECT_NEAR(p[0], x, tol) << "frame " << frame << " joint " << take.marker_names[static_cast<size_t>(joint)];
  EXPECT_NEAR(p[1], y, tol) << "frame " << frame << " joint " << take.marker_names[static_cast<size_t>(joint)];
  EXPECT_NEAR(p[2], z, tol) << "frame " << frame << " joint " << take.marker_names[static_cast<size_t>(joint)];
}

// Compares a stored quaternion with (w, x, y, z), up to the sign.
void ExpectOrientation(const Take& take, int64_t frame, int64_t joint, double w, double x, double y, double z,
                       double tol = 1e-6) {
  const float* q = take.orientations.at(frame, joint);
  const double dot = q[0] * w + q[1] * x + q[2] * y + q[3] * z;
  const double sign = dot < 0 ? -1.0 : 1.0;
  EXPECT_NEAR(q[0], sign * w, tol) << "frame " << frame << " joint " << joint;
  EXPECT_NEAR(q[1], sign * x, tol) << "frame " << frame << " joint " << joint;
  EXPECT_NEAR(q[2], sign * y, tol) << "frame " << frame << " joint " << joint;
  EXPECT_NEAR(q[3], sign * z, tol) << "frame " << frame << " joint " << joint;
}

Take ParseText(const std::string& text, const std::string& units = "mm") {
  BvhReadOptions options;
  options.units = units;
  return ParseBvh(text, "fixture.bvh", options);
}

// Root (6 channels) -> Mid (3 channels) -> End Site, bones along +y.
std::string Chain(const std::string& root_rot, const std::string& mid_rot, const std::string& rows) {
  return "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition " + root_rot +
         "\n  JOINT Mid\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 " + mid_rot +
         "\n    End Site\n    {\n      OFFSET 0 5 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.01\n" + rows;
}

// ZXY on both joints. Frame 1: root at (1, 2, 3), Rz(90); Mid Rx(90).
//   Mid = root + Rz90·(0,10,0) = (1,2,3) + (-10,0,0) = (-9, 2, 3)
//   End = Mid + Rz90·Rx90·(0,5,0) = Mid + Rz90·(0,0,5) = (-9, 2, 8)
//   q(Mid) = qz(90)·qx(90) = (.5, .5, .5, .5)
// Frame 2: root Rz(90)·Rx(90) (one joint, channel order Z X Y), Mid 0:
//   Mid = Rz90·Rx90·(0,10,0) = Rz90·(0,0,10) = (0, 0, 10); End = (0, 0, 15).
// In cm: positions x 10 mm.
TEST(BvhRead, HandWorkedChainZxy) {
  const std::string text = Chain("Zrotation Xrotation Yrotation", "Zrotation Xrotation Yrotation",
                                 "1 2 3 90 0 0 0 90 0\n0 0 0 90 90 0 0 0 0\n");
  Take take = ParseText(text, "cm");
  ASSERT_EQ(take.skeleton.size(), 3u);
  EXPECT_EQ(take.marker_names, (std::vector<std::string>{"Hips", "Mid", "Mid_End"}));
  EXPECT_EQ(take.skeleton[1].parent, 0);
  EXPECT_EQ(take.skeleton[2].parent, 1);
  EXPECT_TRUE(take.skeleton[2].end_site);
  EXPECT_DOUBLE_EQ(take.skeleton[1].offset_mm[1], 100.0);
  EXPECT_EQ(take.skeleton[0].channels,
            (std::vector<std::string>{"Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"}));
  EXPECT_DOUBLE_EQ(take.rate_hz, 100.0);
  EXPECT_EQ(take.source_units, "cm");
  ASSERT_EQ(take.frames(), 2);
  ExpectPosition(take, 0, 0, 10, 20, 30);
  ExpectPosition(take, 0, 1, -90, 20, 30);
  ExpectPosition(take, 0, 2, -90, 20, 80);
  const double h = std::sqrt(0.5);
  ExpectOrientation(take, 0, 0, h, 0, 0, h);
  ExpectOrientation(take, 0, 1, 0.5, 0.5, 0.5, 0.5);
  ExpectOrientation(take, 0, 2, 0.5, 0.5, 0.5, 0.5);  // an end site carries its parent's
  ExpectPosition(take, 1, 0, 0, 0, 0);
  ExpectPosition(take, 1, 1, 0, 0, 100);
  ExpectPosition(take, 1, 2, 0, 0, 150);
  ExpectOrientation(take, 1, 0, 0.5, 0.5, 0.5, 0.5);
}

// YXZ: root Ry(90)·Rx(90): Mid = Ry90·(0,0,10) = (10, 0, 0), End = (15, 0, 0);
// q = qy(90)·qx(90) = (.5, .5, .5, -.5). Frame 2: root Y=90 only, Mid
// X=-90: Mid = Ry90·(0,10,0) = (0,10,0); End = Mid + Ry90·Rx(-90)·(0,5,0) =
// Mid + Ry90·(0,0,-5) = (−5, 10, 0).
TEST(BvhRead, HandWorkedChainYxz) {
  const std::string text = Chain("Yrotation Xrotation Zrotation", "Yrotation Xrotation Zrotation",
                                 "0 0 0 90 90 0 0 0 0\n0 0 0 90 0 0 0 -90 0\n");
  Take take = ParseText(text, "mm");
  ExpectPosition(take, 0, 1, 10, 0, 0);
  ExpectPosition(take, 0, 2, 15, 0, 0);
  ExpectOrientation(take, 0, 0, 0.5, 0.5, 0.5, -0.5);
  ExpectPosition(take, 1, 1, 0, 10, 0);
  ExpectPosition(take, 1, 2, -5, 10, 0);
}

// Position channels on a non-root joint replace its OFFSET (milad.bvh and
// makehuman write the rest offset there); a 3-channel root has only rotations.
TEST(BvhRead, PositionChannelsReplaceTheOffset) {
  const std::string text =
      "HIERARCHY\nROOT A\n{\n OFFSET 5 0 0\n CHANNELS 3 Xrotation Yrotation Zrotation\n JOINT B\n {\n  OFFSET 0 10 0\n"
      "  CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n  End Site\n  {\n   OFFSET 1 0 0\n  "
      "}\n"
      " }\n}\nMOTION\nFrames: 1\nFrame Time: 0.5\n0 0 90 0 20 3 0 0 0\n";
  Take take = ParseText(text);
  // Root at its OFFSET (5,0,0), rotated Rz(90). B = (5,0,0) + Rz90·(0,20,3) = (-15, 0, 3).
  ExpectPosition(take, 0, 0, 5, 0, 0);
  ExpectPosition(take, 0, 1, -15, 0, 3);
  // End = B + Rz90·(1,0,0) = (-15, 1, 3).
  ExpectPosition(take, 0, 2, -15, 1, 3);
  EXPECT_DOUBLE_EQ(take.rate_hz, 2.0);
}

// The same motion written with the quirks of real exporters reads the same.
TEST(BvhRead, ExporterQuirksReadLikeThePlainFile) {
  const std::string plain = Chain("Zrotation Xrotation Yrotation", "Zrotation Xrotation Yrotation",
                                  "1 2 3 90 0 0 0 90 0\n0 0 0 90 90 0 0 0 0\n");
  const std::string quirky =
      "HIERARCHY  \r\nROOT Hips {\r\n\tOFFSET\t0.0 -0.000000 .0\t\r\n\tCHANNELS 6 Xposition Yposition Zposition "
      "Zrotation Xrotation Yrotation \n\n\tJOINT Mid\r\n\t{ OFFSET 0 1e1 0\r\n\t\tCHANNELS 3 Zrotation Xrotation "
      "Yrotation\r\n\t\tEnd Site\n\t\t{\r\n\t\t\tOFFSET 0 5.0 -0\r\n\t\t}\n\t}\r}\r\nMOTION\r\n\r\nFrames:2\r\n"
      "Frame Time:\t.01  \r\n  1 2 3 90 -0 0 0 90 0\t \r\n\r\n0 0 0 90.0 90 0 -0.000000 0 .0\n\n";
  Take a = ParseText(plain);
  Take b = ParseText(quirky);
  ASSERT_EQ(a.marker_names, b.marker_names);
  ASSERT_EQ(a.frames(), b.frames());
  EXPECT_DOUBLE_EQ(b.rate_hz, 100.0);
  for (size_t k = 0; k < a.markers.data().size(); ++k) EXPECT_NEAR(a.markers.data()[k], b.markers.data()[k], 1e-5);
  for (size_t k = 0; k < a.orientations.data().size(); ++k) {
    EXPECT_NEAR(a.orientations.data()[k], b.orientations.data()[k], 1e-7);
  }
}

TEST(BvhRead, DuplicateNamesAndNamesWithSpaces) {
  const std::string text =
      "HIERARCHY\nROOT Left Arm\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nJOINT Left Arm\n{\n"
      "OFFSET 0 1 0\nCHANNELS 0\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 1\n0 0 0\n";
  Take take = ParseText(text);
  EXPECT_EQ(take.marker_names, (std::vector<std::string>{"Left Arm", "Left Arm_2", "Left Arm_2_End"}));
  EXPECT_TRUE(HasWarning(take, "duplicate joint name 'Left Arm'"));
}

TEST(BvhUnits, GuessFromAPersonsSize) {
  EXPECT_EQ(GuessBvhUnits(1.7).units, "m");
  EXPECT_EQ(GuessBvhUnits(16.6).units, "dm");  // MakeHuman's unit
  EXPECT_EQ(GuessBvhUnits(0.9).units, "m");
  EXPECT_EQ(GuessBvhUnits(67).units, "in");
  EXPECT_EQ(GuessBvhUnits(170).units, "cm");
  EXPECT_EQ(GuessBvhUnits(95).units, "in");  // a child in inches (or a cm skeleton of 95: ambiguous)
  EXPECT_EQ(GuessBvhUnits(1700).units, "mm");
  EXPECT_DOUBLE_EQ(GuessBvhUnits(67).mm_per_unit, 25.4);
  EXPECT_DOUBLE_EQ(GuessBvhUnits(170).mm_per_unit, 10.0);
  // Rest pose of the chain: 0, 10, 15 along y.
  std::vector<SkeletonJoint> s(3);
  s[1].parent = 0;
  s[1].offset_mm[1] = 10;
  s[2].parent = 1;
  s[2].offset_mm[1] = 5;
  s[2].offset_mm[0] = -2;
  EXPECT_DOUBLE_EQ(SkeletonRestSize(s), 15.0);
}

TEST(BvhUnits, ReaderWarnsWhatItGuessed) {
  // A 170-unit tall chain: guessed cm, positions x 10.
  std::string text =
      "HIERARCHY\nROOT Hips\n{\nOFFSET 0 90 0\nCHANNELS 3 Xposition Yposition Zposition\nJOINT Head\n{\n"
      "OFFSET 0 80 0\nCHANNELS 0\nEnd Site\n{\nOFFSET 0 0 0\n}\n}\nJOINT Foot\n{\nOFFSET 0 -90 0\nEnd Site\n{\n"
      "OFFSET 0 0 0\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n0 90 0\n";
  Take take = ParseBvh(text, "fixture.bvh");
  EXPECT_EQ(take.source_units, "cm");
  EXPECT_TRUE(HasWarning(take, "guessed 'cm'")) << take.provenance.warnings.size();
  EXPECT_TRUE(HasWarning(take, "170"));
  ExpectPosition(take, 0, 1, 0, 1700, 0);
  BvhReadOptions inches;
  inches.units = "in";
  Take in = ParseBvh(text, "fixture.bvh", inches);
  EXPECT_FALSE(HasWarning(in, "guessed"));
  ExpectPosition(in, 0, 1, 0, 170 * 25.4, 0, 1e-3);
  BvhReadOptions bad;
  bad.units = "furlong";
  EXPECT_THROW(ParseBvh(text, "fixture.bvh", bad), InvalidInput);
}

// Euler decomposition in every order, at random and at gimbal lock: the
// angles recompose to the same rotation.
TEST(BvhEuler, DecompositionRecomposesInEveryOrder) {
  const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (const auto& axes : orders) {
    for (int trial = 0; trial < 200; ++trial) {
      double a = u(rng), b = u(rng) / 2, c = u(rng);
      if (trial % 20 == 0) b = (trial % 40 == 0 ? 1 : -1) * kPi / 2;  // gimbal lock
      Eigen::Quaterniond q = Eigen::AngleAxisd(a, Eigen::Vector3d::Unit(axes[0])) *
                             Eigen::AngleAxisd(b, Eigen::Vector3d::Unit(axes[1])) *
                             Eigen::AngleAxisd(c, Eigen::Vector3d::Unit(axes[2]));
      const double wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
      double angles[3];
      QuaternionToEuler(wxyz, axes, angles);
      EXPECT_LE(std::abs(angles[1]), kPi / 2 + 1e-12);
      Eigen::Quaterniond back = Eigen::AngleAxisd(angles[0], Eigen::Vector3d::Unit(axes[0])) *
                                Eigen::AngleAxisd(angles[1], Eigen::Vector3d::Unit(axes[1])) *
                                Eigen::AngleAxisd(angles[2], Eigen::Vector3d::Unit(axes[2]));
      EXPECT_NEAR(std::abs(back.dot(q)), 1.0, 1e-12) << axes[0] << axes[1] << axes[2] << " trial " << trial;
      if (trial % 20 != 0) {
        EXPECT_NEAR(angles[1], b, 1e-9);  // away from the lock the middle angle is unique
      }
    }
  }
}

// A random skeleton with every channel order, 3- and 6-channel joints, a
// 0-channel joint and two roots; random motion.
std::string RandomBvh(uint32_t seed, int frames) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-180, 180), offset(-30, 30);
  const char* orders[6] = {"Xrotation Yrotation Zrotation", "Xrotation Zrotation Yrotation",
                           "Yrotation Xrotation Zrotation", "Yrotation Zrotation Xrotation",
                           "Zrotation Xrotation Yrotation", "Zrotation Yrotation Xrotation"};
  std::ostringstream h;
  std::vector<int> channel_counts;
  h << "HIERARCHY\n";
  int joint = 0;
  for (int root = 0; root < 2; ++root) {
    h << "ROOT R" << root << "\n{\nOFFSET 1 2 3\nCHANNELS 6 Zposition Xposition Yposition " << orders[root * 3] << "\n";
    channel_counts.push_back(6);
    // A chain of 7 joints, the 3rd with 6 channels, the 5th with none.
    for (int k = 0; k < 7; ++k, ++joint) {
      h << "JOINT J" << joint << "\n{\nOFFSET " << offset(rng) << " " << offset(rng) << " " << offset(rng) << "\n";
      if (k == 2) {
        h << "CHANNELS 6 " << orders[(joint + 1) % 6] << " Xposition Yposition Zposition\n";
        channel_counts.push_back(6);
      } else if (k == 4) {
        h << "CHANNELS 0\n";
        channel_counts.push_back(0);
      } else {
        h << "CHANNELS 3 " << orders[joint % 6] << "\n";
        channel_counts.push_back(3);
      }
    }
    h << "End Site\n{\nOFFSET 0 4 0\n}\n";
    for (int k = 0; k < 7; ++k) h << "}\n";
    h << "}\n";
  }
  int total = 0;
  for (int c : channel_counts) total += c;
  h << "MOTION\nFrames: " << frames << "\nFrame Time: 0.008333\n";
  h.precision(9);
  for (int f = 0; f < frames; ++f) {
    for (int c = 0; c < total; ++c) h << (c ? " " : "") << (c % 3 == 0 ? offset(rng) * 3 : angle(rng));
    h << "\n";
  }
  return h.str();
}

// Returns {worst position error (mm, relative beyond 1 m), worst quaternion component error}.
std::pair<double, double> ExpectSameMotion(const Take& a, const Take& b, double position_tol_mm,
                                           double quaternion_tol) {
  EXPECT_EQ(a.marker_names, b.marker_names);
  EXPECT_EQ(a.skeleton.size(), b.skeleton.size());
  if (a.frames() != b.frames() || a.markers.markers() != b.markers.markers() ||
      a.skeleton.size() != b.skeleton.size()) {
    ADD_FAILURE() << "different shapes";
    return {1e300, 1e300};
  }
  for (size_t j = 0; j < a.skeleton.size(); ++j) {
    EXPECT_EQ(a.skeleton[j].parent, b.skeleton[j].parent);
    EXPECT_EQ(a.skeleton[j].channels, b.skeleton[j].channels);
    EXPECT_EQ(a.skeleton[j].end_site, b.skeleton[j].end_site);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.skeleton[j].offset_mm[k], b.skeleton[j].offset_mm[k], 1e-9);
  }
  double worst_p = 0, worst_q = 0;
  for (int64_t f = 0; f < a.frames(); ++f) {
    for (int64_t j = 0; j < a.markers.markers(); ++j) {
      for (int k = 0; k < 3; ++k) {
        const double pa = a.markers.at(f, j)[k], pb = b.markers.at(f, j)[k];
        worst_p = std::max(worst_p, std::abs(pa - pb) / std::max(1.0, std::abs(pa) / 1000));
      }
      const float* qa = a.orientations.at(f, j);
      const float* qb = b.orientations.at(f, j);
      const double dot = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3];
      for (int k = 0; k < 4; ++k) worst_q = std::max(worst_q, std::abs(double{qa[k]} - (dot < 0 ? -qb[k] : qb[k])));
    }
  }
  EXPECT_LE(worst_p, position_tol_mm);
  EXPECT_LE(worst_q, quaternion_tol);
  return {worst_p, worst_q};
}

TEST(BvhWrite, ReadWriteReadRoundTrip) {
  TempDir dir;
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    const std::string path = (dir / ("random" + std::to_string(seed) + ".bvh")).string();
    WriteBytes(path, RandomBvh(seed, 50));
    BvhReadOptions cm;
    cm.units = "cm";
    Take a = ReadBvh(path, cm);
    ASSERT_EQ(a.skeleton.size(), 18u);
    ASSERT_EQ(a.frames(), 50);
    const std::string out = (dir / ("random" + std::to_string(seed) + ".out.bvh")).string();
    WriteBvh(out, a);  // in the take's source unit, cm
    Take b = ReadBvh(out, cm);
    EXPECT_NEAR(b.rate_hz, a.rate_hz, 1e-12 * a.rate_hz);
    // Positions within 1e-3 mm (or 1e-6 relative beyond 1 m); quaternions within 1e-5.
    const auto [p, q] = ExpectSameMotion(a, b, 1e-3, 1e-5);
    std::printf("[ bvh      ] random skeleton %u round trip: positions %.2g mm, quaternions %.2g\n", seed, p, q);
    // The second trip reproduces the first one's text closely enough to be stable.
    WriteBvh(out + "2", b, BvhWriteOptions{"m"});
    BvhReadOptions m;
    m.units = "m";
    Take c = ReadBvh(out + "2", m);
    ExpectSameMotion(a, c, 1e-3, 1e-5);
  }
}

TEST(BvhWrite, HandWorkedChainWritesItsAngles) {
  Take take = ParseText(Chain("Zrotation Xrotation Yrotation", "Yrotation Xrotation Zrotation",
                              "1 2 3 90 0 0 0 90 0\n0 0 0 90 90 0 0 0 0\n"));
  const std::string text = FormatBvh(take);
  // Frame 1: root (1,2,3), Z=90; Mid: local = Rx(90) in YXZ order -> Y 0, X 90, Z 0.
  EXPECT_NE(text.find("\n1 2 3 90.000000 0.000000 0.000000 0.000000 90.000000 0.000000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("Frame Time: 0.01\n"), std::string::npos);
  EXPECT_NE(text.find("CHANNELS 3 Yrotation Xrotation Zrotation"), std::string::npos);
}

// A take read from a file is consistent; moving a joint off its bone shows.
TEST(BvhWrite, PositionMismatchOfHandBuiltTakes) {
  Take take = ParseText(RandomBvh(5, 20), "cm");
  EXPECT_LT(SkeletonPositionMismatchMm(take), 1e-3);
  // Marker 3 is J1 (R0, J0, J1, ...), a 3-channel joint: 5 mm off along x.
  ASSERT_EQ(take.marker_names[2], "J1");
  take.markers.at(7, 2)[0] += 5.0f;
  // Its own bone is 5 mm off; its child J2 has position channels (not checked).
  EXPECT_NEAR(SkeletonPositionMismatchMm(take), 5.0, 1e-3);
  take.orientations.Resize(1, 1);
  EXPECT_THROW(SkeletonPositionMismatchMm(take), InvalidInput);
}

TEST(BvhWrite, RefusesTakesItCannotWrite) {
  Take none;
  none.rate_hz = 100;
  EXPECT_THROW(FormatBvh(none), InvalidInput);
  Take take = ParseText(Chain("Zrotation Xrotation Yrotation", "Zrotation Xrotation Yrotation",
                              "1 2 3 90 0 0 0 90 0\n0 0 0 90 90 0 0 0 0\n"));
  Take missing = take;
  missing.orientations.at(1, 1)[0] = kMissing;
  try {
    FormatBvh(missing);
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1: joint 'Mid'"), std::string::npos) << e.what();
  }
  Take bad_parent = take;
  bad_parent.skeleton[1].parent = 2;
  EXPECT_THROW(FormatBvh(bad_parent), InvalidInput);
  Take no_rate = take;
  no_rate.rate_hz = 0;
  EXPECT_THROW(FormatBvh(no_rate), InvalidInput);
  EXPECT_THROW(FormatBvh(take, BvhWriteOptions{"yd"}), InvalidInput);
}

// Hostile inputs: one ParseError naming the file and the line.
struct Hostile {
  const char* name;
  std::string text;
  int64_t line;
};

TEST(BvhRead, HostileInputsThrowOneParseErrorNamingFileAndLine) {
  const std::string head =
      "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n";
  const std::string motion = "MOTION\nFrames: 2\nFrame Time: 0.01\n";  // lines 11-13
  std::string deep = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n";
  for (int k = 0; k < kBvhMaxDepth + 5; ++k) deep += "JOINT J\n{\nOFFSET 0 1 0\n";
  const std::vector<Hostile> cases = {
      {"empty", "  \n\n", 1},
      {"not_bvh", "HELLO\n", 1},
      {"truncated_rows", head + motion + "10.5 20.25 30.125\n", 15},
      {"truncated_half", head + motion + "1 2", 12},
      {"truncated_header", head + "MOTION\nFrames: 2\n", 13},
      {"no_motion", head, 11},
      {"short_row", head + motion + "1 2 3\n1 2\n1 2 3\n", 15},
      {"long_row", head + motion + "1 2 3 4\n1 2 3\n", 14},
      {"nan", head + motion + "1 2 3\n1 nan 3\n", 15},
      {"inf", head + motion + "1 inf 3\n1 2 3\n", 14},
      {"text_value", head + motion + "1 2 3\n1 2 x3\n", 15},
      {"unknown_channel", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Wrotation Zrotation\n}\n", 5},
      {"repeated_channel", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Xrotation\n}\n", 5},
      {"seven_channels", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 7 Xrotation\n}\n", 5},
      {"channels_in_end_site", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nEnd Site\n{\nCHANNELS 0\n}\n}\n", 7},
      {"absurd_frames", head + "MOTION\nFrames: 999999999999\nFrame Time: 0.01\n1 2 3\n", 12},
      {"negative_frames", head + "MOTION\nFrames: -1\nFrame Time: 0.01\n", 12},
      {"zero_frame_time", head + "MOTION\nFrames: 1\nFrame Time: 0\n1 2 3\n", 13},
      {"nan_frame_time", head + "MOTION\nFrames: 1\nFrame Time: nan\n1 2 3\n", 13},
      {"extra_rows", head + motion + "1 2 3\n1 2 3\n1 2 3\n", 16},
      {"unbalanced", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nMOTION\nFrames: 0\nFrame Time: 1\n", 5},
      {"extra_brace", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n}\n}\n", 6},
      {"no_offset", "HIERARCHY\nROOT A\n{\nCHANNELS 0\n}\nMOTION\nFrames: 0\nFrame Time: 1\n", 5},
      {"nan_offset", "HIERARCHY\nROOT A\n{\nOFFSET 0 nan 0\n}\n", 4},
      {"huge_offset", "HIERARCHY\nROOT A\n{\nOFFSET 0 1e300 0\n}\nMOTION\nFrames: 0\nFrame Time: 1\n", 2},
      {"deep", deep, 5 + 3 * (kBvhMaxDepth - 1)},
      {"joint_outside_root", "HIERARCHY\nJOINT A\n{\n}\n", 2},
      {"no_channels_but_frames", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: 3\nFrame Time: 1\n\n\n\n", 7},
  };
  TempDir dir;
  for (const Hostile& h : cases) {
    SCOPED_TRACE(h.name);
    const std::string path = (dir / (std::string(h.name) + ".bvh")).string();
    WriteBytes(path, h.text);
    const std::string msg = ExpectParseError([&] { ReadBvh(path); }, path, h.line);
    EXPECT_FALSE(msg.empty());
  }
  EXPECT_THROW(ReadBvh((dir / "absent.bvh").string()), IoError);
}

// ../shared/data/bvh: nine files from six exporters against REFERENCE.tsv.
struct Reference {
  std::string path;
  int joints, end_sites, channels, frames;
  std::string frame_time, first_order, root_offset;
};

std::vector<Reference> LoadReference(const std::string& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);  // header
  std::vector<Reference> refs;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, '\t')) f.push_back(cell);
    if (f.size() < 9) continue;
    refs.push_back({f[0], std::stoi(f[1]), std::stoi(f[2]), std::stoi(f[3]), std::stoi(f[4]), f[5], f[7], f[8]});
  }
  return refs;
}

TEST(BvhSharedData, EveryFileMatchesReferenceTsv) {
  CSW_REQUIRE_SHARED_DATA("bvh/REFERENCE.tsv");
  const std::vector<Reference> refs = LoadReference(SharedData("bvh/REFERENCE.tsv").string());
  ASSERT_EQ(refs.size(), 9u);
  for (const Reference& r : refs) {
    SCOPED_TRACE(r.path);
    const std::string path = SharedData("bvh/" + r.path).string();
    Take take = ReadBvh(path);  // unit guessed
    int joints = 0, end_sites = 0, channels = 0;
    for (const SkeletonJoint& s : take.skeleton) {
      (s.end_site ? end_sites : joints) += 1;
      channels += static_cast<int>(s.channels.size());
    }
    EXPECT_EQ(joints, r.joints);
    EXPECT_EQ(end_sites, r.end_sites);
    EXPECT_EQ(channels, r.channels);
    EXPECT_EQ(take.frames(), r.frames);
    EXPECT_EQ(take.markers.markers(), r.joints + r.end_sites);
    EXPECT_EQ(take.orientations.frames(), r.frames);
    EXPECT_NEAR(take.rate_hz, 1.0 / std::stod(r.frame_time), 1e-9 * take.rate_hz);
    std::string order;
    for (const std::string& c : take.skeleton[0].channels) order += (order.empty() ? "" : " ") + c;
    EXPECT_EQ(order, r.first_order);
    std::stringstream ro(r.root_offset);
    const double mm = MillimetresPerUnit(take.source_units);
    for (int k = 0; k < 3; ++k) {
      double v;
      ro >> v;
      EXPECT_NEAR(take.skeleton[0].offset_mm[k], v * mm, 1e-9);
    }
    EXPECT_TRUE(HasWarning(take, "guessed '" + take.source_units + "'"));
    // Every quaternion is a unit one; every position finite.
    for (int64_t f = 0; f < take.frames(); f += std::max<int64_t>(1, take.frames() / 50)) {
      for (int64_t j = 0; j < take.markers.markers(); ++j) {
        const float* q = take.orientations.at(f, j);
        EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-5);
        EXPECT_TRUE(take.markers.Visible(f, j));
      }
    }
    std::printf("[ bvh      ] %-32s %4d joints %3d end sites %4d channels %5d frames %.4g Hz, size %.4g -> %s\n",
                r.path.c_str(), joints, end_sites, channels, r.frames, take.rate_hz,
                SkeletonRestSize(take.skeleton) / mm, take.source_units.c_str());
  }
}

// The real exports survive read -> write -> read too (CRLF, 6 channels
// everywhere, 173 joints).
TEST(BvhSharedData, RealFilesRoundTrip) {
  CSW_REQUIRE_SHARED_DATA("bvh/REFERENCE.tsv");
  TempDir dir;
  for (const Reference& r : LoadReference(SharedData("bvh/REFERENCE.tsv").string())) {
    SCOPED_TRACE(r.path);
    Take a = ReadBvh(SharedData("bvh/" + r.path).string());
    const std::string out = (dir / "out.bvh").string();
    WriteBvh(out, a);
    BvhReadOptions same;
    same.units = a.source_units;
    Take b = ReadBvh(out, same);
    const auto [p, q] = ExpectSameMotion(a, b, 1e-3, 1e-5);
    std::printf("[ bvh      ] %-32s round trip: positions %.2g mm, quaternions %.2g\n", r.path.c_str(), p, q);
  }
}

}  // namespace
}  // namespace csw
