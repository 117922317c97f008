#include "workbench/jobs/export_job.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/file_util.h"
#include "core/take.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/formats/bvh.h"
#include "io/formats/trc.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;

// ---- export ----------------------------------------------------------------

std::string ExportOptions::Check() const {
  if (corpus.empty() || take.empty() || output.empty()) return "export: corpus, --take and -o are required";
  if (format != "c3d" && format != "trc" && format != "csv" && format != "bvh") {
    return "export: --format must be c3d, trc, csv or bvh";
  }
  if (!units.empty() && format != "bvh") return "export: --units applies to --format bvh only";
  if (!units.empty() && !IsBvhUnit(units)) return "export: --units must be mm, cm, dm, m or in, not '" + units + "'";
  return "";
}

void Export(const ExportOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  Corpus corpus = Corpus::Open(options.corpus);
  if (!corpus.HasTake(options.take)) throw InvalidInput(options.corpus + ": no take named \"" + options.take + "\"");
  progress.Update("export", 0.0);
  Take take = corpus.LoadTake(options.take);
  if (options.format == "bvh" && take.skeleton.empty()) {
    throw InvalidInput(options.corpus + ": take \"" + options.take +
                       "\" has no skeleton; BVH export needs a skeleton capture (a BVH import or a virtual signer)");
  }
  // Write into a temporary sibling folder under the final file name (formats such as
  // TRC record their own file name), then rename: a failed export never leaves half a file.
  fs::path out_path(options.output);
  fs::path tmp_dir = out_path.parent_path() / (".csw-export-" + out_path.filename().string());
  std::error_code mk;
  fs::create_directories(tmp_dir, mk);
  if (mk) throw IoError(tmp_dir.string(), "cannot create temporary folder: " + mk.message());
  std::string tmp = (tmp_dir / out_path.filename()).string();
  try {
    if (options.format == "c3d") {
      WriteC3d(tmp, take);
    } else if (options.format == "trc") {
      WriteTrc(tmp, take);
    } else if (options.format == "bvh") {
      BvhWriteOptions bvh;
      bvh.units = options.units;
      WriteBvh(tmp, take, bvh);
    } else {
      std::ofstream out(tmp);
      if (!out) throw IoError(tmp, "cannot open for writing");
      out << "frame,time_s";
      for (const auto& n : take.marker_names) out << "," << n << "_x," << n << "_y," << n << "_z";
      out << "\n";
      char buf[32];
      for (int64_t f = 0; f < take.frames(); ++f) {
        std::snprintf(buf, sizeof(buf), "%.6f", static_cast<double>(f) / take.rate_hz);
        out << (take.first_frame + f) << "," << buf;
        for (int64_t m = 0; m < take.markers.markers(); ++m) {
          const float* p = take.markers.at(f, m);
          for (int k = 0; k < 3; ++k) {
            out << ",";
            if (!IsMissing(p[k])) {
              std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(p[k]));
              out << buf;
            }
          }
        }
        out << "\n";
        if (f % 1024 == 0) progress.Update("export", static_cast<double>(f) / static_cast<double>(take.frames()));
      }
      out.close();
      if (!out) throw IoError(tmp, "write failed");
    }
    ReplaceFileDurably(tmp, options.output);
    std::error_code ec;
    fs::remove(tmp_dir, ec);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp_dir, ec);
    throw;
  }
  progress.Update("export", 1.0);
}

}  // namespace csw::jobs
