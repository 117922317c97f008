#include "workbench/jobs/inspect_job.h"

#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "io/c3d/c3d.h"
#include "io/corpus/hdf5_util.h"
#include "io/formats/bvh.h"
#include "io/formats/eaf.h"
#include "io/formats/textgrid.h"
#include "io/formats/trc.h"
#include "io/formats/wav.h"
#include "io/models/model_file.h"
#include "workbench/jobs/info_job.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json TierJson(const std::vector<LabelTier>& tiers) {
  json out = json::array();
  for (const auto& t : tiers) {
    out.push_back({{"name", t.name},
                   {"kind", t.kind == LabelTier::Kind::kInterval ? "interval" : "point"},
                   {"start_s", t.start_s},
                   {"end_s", t.end_s},
                   {"labels", t.labels.size()}});
  }
  return out;
}

json EventsJson(const std::vector<Event>& events) {
  json out = json::array();
  for (const auto& e : events) {
    out.push_back({{"label", e.label}, {"context", e.context}, {"time_s", e.time_s}, {"description", e.description}});
  }
  return out;
}

json TakeFacts(const Take& t) {
  return {{"markers", t.marker_names.size()}, {"frames", t.frames()},
          {"first_frame", t.first_frame},     {"rate_hz", t.rate_hz},
          {"units", t.source_units},          {"valid_point_samples", t.markers.CountVisible()},
          {"labels", t.marker_names},         {"warnings", t.provenance.warnings}};
}

// The root "format" attribute of an HDF5 file (nullopt when it has none).
// Throws InvalidInput when the file is not HDF5 at all.
std::optional<std::string> Hdf5RootFormat(const std::string& path) {
  auto lock = h5::Lock();
  const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  h5::TakeErrorMessage();
  if (is_hdf5 <= 0) throw InvalidInput(path + ": not an HDF5 file (expected a csw corpus or model file)");
  const h5::Where where{path};
  h5::Handle file = h5::Own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, where, "open", "/");
  return h5::ReadAttrString(file.get(), "format", where, "/");
}

json ModelInfoJson(const ModelInfo& info) {
  return {{"training_takes", info.training_takes},   {"training_frames", info.training_frames},
          {"selected_frames", info.selected_frames}, {"training_rms_mm", info.training_rms_mm},
          {"created_utc", info.created_utc},         {"csw_version", info.csw_version}};
}

json DescribeModels(const std::string& path) {
  const ModelFile m = LoadModelFile(path);
  json models = json::object();
  auto rigid = [](const RigidModel& r) {
    json j = {{"markers", r.markers.size()}, {"parameters", r.motion.count()}};
    j.update(ModelInfoJson(r.info));
    return j;
  };
  if (m.head) models["head_motion"] = rigid(*m.head);
  if (m.forearm) models["forearm_motion"] = rigid(*m.forearm);
  if (m.face) {
    json j = {{"markers", m.face->layout.num_markers()}, {"parameters", m.face->num_parameters()}};
    j.update(ModelInfoJson(m.face->info));
    models["face"] = j;
  }
  if (m.hand) {
    json j = {{"markers", m.hand->layout.num_markers()}, {"parameters", m.hand->num_parameters()}};
    j.update(ModelInfoJson(m.hand->info));
    models["hand"] = j;
  }
  return {{"model_count", models.size()}, {"models", models}};
}

std::string Join(const json& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n.get<std::string>();
  return s.empty() ? "-" : s;
}

}  // namespace

json Inspect(const std::string& path, Progress& progress) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (fs::is_directory(path, ec)) throw IoError(path, "is a directory, not a file");
  std::string format = FormatOf(path);
  json j = {{"file", path}, {"format", format}, {"bytes", fs::file_size(path, ec)}};
  if (format == "c3d") {
    progress.CheckCancel();
    C3dReader reader(path);
    const C3dInfo& i = reader.info();
    int64_t valid = 0;
    double sum = 0.0;
    reader.ValidPointStats(&valid, &sum);
    j.update({{"processor", i.processor},
              {"storage", i.storage},
              {"points", i.points},
              {"first_frame", i.first_frame},
              {"frames", i.frames},
              {"point_rate_hz", i.point_rate_hz},
              {"point_scale", i.point_scale},
              {"units", i.units},
              {"analog_channels", i.analog_channels},
              {"analog_subframes_per_frame", i.analog_subframes_per_frame},
              {"analog_rate_hz", i.analog_rate_hz},
              {"valid_point_samples", valid},
              {"sum_xyz_valid", sum},
              {"labels", i.labels},
              {"analog_labels", i.analog_labels},
              {"events", EventsJson(i.events)},
              {"warnings", i.warnings}});
  } else if (format == "trc") {
    j.update(TakeFacts(ReadTrc(path)));
  } else if (format == "bvh") {
    Take t = ReadBvh(path);
    int64_t end_sites = 0, channels = 0;
    for (const SkeletonJoint& s : t.skeleton) {
      end_sites += s.end_site ? 1 : 0;
      channels += static_cast<int64_t>(s.channels.size());
    }
    j.update(TakeFacts(t));
    j.update({{"joints", static_cast<int64_t>(t.skeleton.size()) - end_sites},
              {"end_sites", end_sites},
              {"channels", channels}});
  } else if (format == "textgrid") {
    double xmin = 0, xmax = 0;
    auto tiers = ReadTextGrid(path, &xmin, &xmax);
    j.update({{"xmin", xmin}, {"xmax", xmax}, {"tiers", TierJson(tiers)}});
  } else if (format == "eaf") {
    std::vector<std::string> warnings;
    auto tiers = ReadEaf(path, &warnings);
    j.update({{"tiers", TierJson(tiers)}, {"warnings", warnings}});
  } else if (format == "wav") {
    Audio a = ReadWav(path);
    j.update(
        {{"rate_hz", a.rate_hz}, {"channels", a.channels}, {"frames", a.frames()}, {"duration_s", a.duration_s()}});
  } else if (format == "hdf5") {
    const std::optional<std::string> root = Hdf5RootFormat(path);
    if (root && *root == "csw-corpus") {
      j["format"] = "corpus";
      j.update(Info(path));
    } else if (root && *root == "csw-models") {
      j["format"] = "models";
      j.update(DescribeModels(path));
    } else {
      throw InvalidInput(path + ": an HDF5 file that is neither a csw corpus nor a csw model file (" +
                         (root ? "root attribute format is '" + *root + "'" : "no root attribute 'format'") +
                         "; expected 'csw-corpus' or 'csw-models')");
    }
  } else {
    throw InvalidInput(path + ": unknown file type (expected .c3d, .trc, .bvh, .TextGrid, .eaf, .wav or .h5)");
  }
  return j;
}

std::string InspectText(const json& facts) {
  std::ostringstream os;
  for (auto it = facts.begin(); it != facts.end(); ++it) {
    const json& v = it.value();
    if (it.key() == "models" && v.is_object()) {
      os << "models:\n";
      for (auto m = v.begin(); m != v.end(); ++m) {
        const json& d = m.value();
        char buf[160];
        std::snprintf(buf, sizeof(buf), "%lld markers, %lld parameters, %lld training frames (%lld selected), %.3f mm",
                      static_cast<long long>(d["markers"].get<int64_t>()),
                      static_cast<long long>(d["parameters"].get<int64_t>()),
                      static_cast<long long>(d["training_frames"].get<int64_t>()),
                      static_cast<long long>(d["selected_frames"].get<int64_t>()), d["training_rms_mm"].get<double>());
        os << "  " << m.key() << ": " << buf << " rms\n";
        os << "    training takes: " << Join(d["training_takes"]) << "\n";
        os << "    created: " << d["created_utc"].get<std::string>() << " (csw " << d["csw_version"].get<std::string>()
           << ")\n";
      }
    } else if (v.is_array() && v.size() > 12) {
      os << it.key() << ": [" << v.size() << " items]\n";
    } else if (v.is_array() || v.is_object()) {
      os << it.key() << ": " << v.dump() << "\n";
    } else if (v.is_string()) {
      os << it.key() << ": " << v.get<std::string>() << "\n";
    } else {
      os << it.key() << ": " << v.dump() << "\n";
    }
  }
  return os.str();
}

}  // namespace csw::jobs
