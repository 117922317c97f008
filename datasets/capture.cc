#include "datasets/capture.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "datasets/virtual_cuer.h"

namespace csw {

namespace {

double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

Eigen::Isometry3d FromPoseVector(const Eigen::Matrix<double, 1, 6>& v) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  Eigen::Vector3d r = v.head<3>().transpose();
  double a = r.norm();
  if (a > 0.0) x.linear() = Eigen::AngleAxisd(a, r / a).toRotationMatrix();
  x.translation() = v.tail<3>().transpose();
  return x;
}

}  // namespace

double StandardNormal(std::mt19937_64& rng) {
  double u1 = Uniform01(rng);
  double u2 = Uniform01(rng);
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

CaptureSetup MakeCaptureSetup(const SimulateOptions& options) {
  CaptureSetup s;
  s.min_cameras = options.min_cameras;
  s.noise_mm = options.noise_mm;
  s.occlusions = options.occlusions;
  s.dropouts_per_s = options.dropouts_per_s;
  s.label_swaps = options.label_swaps;
  const int n = options.cameras;
  for (int i = 0; i < n; ++i) {
    double az = n == 1 ? 0.0 : (-80.0 + 160.0 * i / (n - 1)) * M_PI / 180.0;
    double height = (i % 2 == 0) ? 1950.0 : 1450.0;
    if (i % 4 == 3) height = 900.0;
    s.cameras.emplace_back(2400.0 * std::sin(az), 2400.0 * std::cos(az), height);
  }
  return s;
}

double SegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                       const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= 1e-12 && e <= 1e-12) return r.norm();
  if (a <= 1e-12) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-12) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-12 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

bool SegmentHitsEllipsoid(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& centre,
                          const Eigen::Matrix3d& axes, const Eigen::Vector3d& radii) {
  const Eigen::Vector3d o = (axes.transpose() * (p0 - centre)).cwiseQuotient(radii);
  const Eigen::Vector3d d = (axes.transpose() * (p1 - p0)).cwiseQuotient(radii);
  const double a = d.squaredNorm(), b = 2.0 * o.dot(d), c = o.squaredNorm() - 1.0;
  if (c <= 0.0) return true;  // starts inside
  if (a <= 1e-15) return false;
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return false;
  const double sq = std::sqrt(disc);
  const double t0 = (-b - sq) / (2.0 * a), t1 = (-b + sq) / (2.0 * a);
  return (t0 >= 0.0 && t0 <= 1.0) || (t1 >= 0.0 && t1 <= 1.0);
}

void ApplyCaptureArtefacts(const VirtualCuer& cuer, const CaptureSetup& setup, std::mt19937_64 rng,
                           SimulationResult* result) {
  SimulationResult& r = *result;
  const int64_t frames = r.clean.frames();
  const int64_t nm = r.clean.markers();
  const int nf = static_cast<int>(r.face_columns.size());
  const bool hand = !r.hand_columns.empty();
  const VirtualHand& hm = cuer.hand();
  const VirtualFace& fm = cuer.face();
  r.state.assign(static_cast<size_t>(frames * nm), kVisible);

  // Per hand marker: its segment name and the capsules it may not be hidden by.
  std::vector<std::string> marker_segment(static_cast<size_t>(hm.num_markers()), "forearm");
  std::map<std::string, std::string> parent_of = {{"forearm", ""}, {"palm", "forearm"}};
  for (const auto& seg : hm.segments()) {
    parent_of[seg.name] = seg.parent.empty() ? "forearm" : seg.parent;
    for (const auto& m : seg.markers) {
      auto it = std::find(hm.marker_names().begin(), hm.marker_names().end(), m);
      if (it != hm.marker_names().end()) marker_segment[static_cast<size_t>(it - hm.marker_names().begin())] = seg.name;
    }
  }
  // Face marker normals in the head frame.
  std::vector<Eigen::Vector3d> face_normal(static_cast<size_t>(nf));
  std::vector<bool> is_throat(static_cast<size_t>(nf), false);
  const Eigen::Vector3d hr = fm.head_radii(), hc = fm.head_centre();
  for (int i = 0; i < nf; ++i) {
    const int k = r.face_markers[static_cast<size_t>(i)];
    Eigen::Vector3d p = fm.neutral().col(k);
    const std::string& name = fm.marker_names()[static_cast<size_t>(k)];
    if (std::find(fm.throat_markers().begin(), fm.throat_markers().end(), name) != fm.throat_markers().end()) {
      is_throat[static_cast<size_t>(i)] = true;
      face_normal[static_cast<size_t>(i)] = Eigen::Vector3d(p.x(), p.y() - 5.0, 0.0).normalized();
    } else {
      Eigen::Vector3d g = (p - hc).cwiseQuotient(hr.cwiseProduct(hr));
      face_normal[static_cast<size_t>(i)] = g.normalized();
    }
  }

  if (setup.occlusions) {
    std::vector<Capsule> caps;
    for (int64_t f = 0; f < frames; ++f) {
      Eigen::Matrix<double, 1, 6> hv = r.head_motion.row(f);
      HeadMotion motion;
      motion.rotation = hv.head<3>().transpose();
      motion.translation = hv.tail<3>().transpose();
      const Eigen::Isometry3d head = r.head_reference * motion.Weighted(1.0);
      const Eigen::Isometry3d neck = r.head_reference * motion.Weighted(0.5);
      const Eigen::Vector3d neck_a = neck * fm.neck_top(), neck_b = neck * fm.neck_bottom();
      const Eigen::Vector3d centre = head * hc;
      caps.clear();
      if (hand) {
        Eigen::VectorXd q = r.joint_angles.row(f).transpose();
        const Eigen::Isometry3d forearm = FromPoseVector(r.forearm_pose.row(f));
        for (Capsule c : hm.CapsulesInForearm(q)) {
          c.a = forearm * c.a;
          c.b = forearm * c.b;
          caps.push_back(c);
        }
      }
      for (int64_t m = 0; m < nm; ++m) {
        const float* pf = r.clean.at(f, m);
        const Eigen::Vector3d p(pf[0], pf[1], pf[2]);
        const bool is_face = m < nf;
        Eigen::Vector3d normal;
        std::string own, parent;
        if (is_face) {
          normal = head.linear() * face_normal[static_cast<size_t>(m)];
        } else {
          own = marker_segment[static_cast<size_t>(m - nf)];
          parent = parent_of[own];
          double best = 1e300;
          normal = Eigen::Vector3d::UnitZ();
          for (const Capsule& c : caps) {
            if (c.segment != own) continue;
            Eigen::Vector3d ab = c.b - c.a;
            double t = std::clamp((p - c.a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
            Eigen::Vector3d off = p - (c.a + t * ab);
            if (off.norm() < best) {
              best = off.norm();
              normal = off.normalized();
            }
          }
        }
        int seen = 0;
        for (const Eigen::Vector3d& cam : setup.cameras) {
          Eigen::Vector3d dir = (cam - p).normalized();
          if (normal.dot(dir) < (is_face ? 0.1 : -0.15)) continue;
          const Eigen::Vector3d start = p + 3.0 * dir;
          bool blocked = false;
          for (const Capsule& c : caps) {
            if (!is_face && (c.segment == own || c.segment == parent)) continue;
            if (SegmentDistance(start, cam, c.a, c.b) < c.radius) {
              blocked = true;
              break;
            }
          }
          if (!blocked && (!is_face || is_throat[static_cast<size_t>(m)]))
            blocked = SegmentHitsEllipsoid(start, cam, centre, head.linear(), hr);
          if (!blocked && !is_face) blocked = SegmentDistance(start, cam, neck_a, neck_b) < fm.neck_radius();
          if (!blocked && ++seen >= setup.min_cameras) break;
        }
        if (seen < setup.min_cameras) r.state[static_cast<size_t>(f * nm + m)] = kOccluded;
      }
    }
  }
  // Dropped samples: short runs at random.
  if (setup.dropouts_per_s > 0.0) {
    const double p_start = setup.dropouts_per_s / r.take.rate_hz;
    for (int64_t m = 0; m < nm; ++m)
      for (int64_t f = 0; f < frames; ++f) {
        if (Uniform01(rng) >= p_start) continue;
        int64_t len = 1 + static_cast<int64_t>(rng() % 6);
        for (int64_t g = f; g < std::min(frames, f + len); ++g)
          if (r.state[static_cast<size_t>(g * nm + m)] == kVisible) r.state[static_cast<size_t>(g * nm + m)] = kDropped;
        f += len;
      }
  }
  // Noise on the samples that are seen.
  r.take.markers = MarkerArray(frames, nm);
  for (int64_t f = 0; f < frames; ++f)
    for (int64_t m = 0; m < nm; ++m) {
      if (r.state[static_cast<size_t>(f * nm + m)] != kVisible) continue;
      const float* src = r.clean.at(f, m);
      float* dst = r.take.markers.at(f, m);
      for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(src[c] + setup.noise_mm * StandardNormal(rng));
    }
  // One temporary label swap between neighbouring hand markers.
  if (setup.label_swaps && hand && frames > 0) {
    static const std::pair<const char*, const char*> kPairs[] = {{"ITIP", "MTIP"}, {"MTIP", "RTIP"}, {"I3D", "M3D"},
                                                                 {"M3D", "R3D"},   {"KNI", "KNM"},   {"FA2", "FA3"}};
    const auto& pr = kPairs[rng() % std::size(kPairs)];
    // The default layout's names; another layout's hand names end with them ("RH_ITIP").
    auto col = [&](const char* name) {
      const std::string n = name;
      auto it = std::find_if(r.take.marker_names.begin(), r.take.marker_names.end(), [&](const std::string& m) {
        return m == n || (m.size() > n.size() && m.compare(m.size() - n.size(), n.size(), n) == 0 &&
                          m[m.size() - n.size() - 1] == '_');
      });
      return static_cast<int>(it - r.take.marker_names.begin());
    };
    LabelSwap s;
    s.marker_a = col(pr.first);
    s.marker_b = col(pr.second);
    const auto len = std::min<int64_t>(frames, static_cast<int64_t>((0.3 + 0.7 * Uniform01(rng)) * r.take.rate_hz));
    s.first_frame = static_cast<int64_t>(Uniform01(rng) * static_cast<double>(frames - len));
    s.end_frame = s.first_frame + len;
    if (s.marker_a < nm && s.marker_b < nm) {
      for (int64_t f = s.first_frame; f < s.end_frame; ++f) {
        float* a = r.take.markers.at(f, s.marker_a);
        float* b = r.take.markers.at(f, s.marker_b);
        for (int c = 0; c < 3; ++c) std::swap(a[c], b[c]);
      }
      r.swaps.push_back(s);
    }
  }
}

}  // namespace csw
