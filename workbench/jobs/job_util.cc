#include "workbench/jobs/job_util.h"

#include <cctype>
#include <filesystem>

namespace csw::jobs {

std::string FormatOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".c3d") return "c3d";
  if (ext == ".trc") return "trc";
  if (ext == ".bvh") return "bvh";
  if (ext == ".textgrid") return "textgrid";
  if (ext == ".eaf") return "eaf";
  if (ext == ".wav") return "wav";
  if (ext == ".h5" || ext == ".hdf5") return "hdf5";
  return "";
}

}  // namespace csw::jobs
