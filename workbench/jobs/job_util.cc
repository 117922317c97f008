#include "workbench/jobs/job_util.h"

#include <cctype>
#include <filesystem>
#include <fstream>

#include "io/formats/text_util.h"

namespace csw::jobs {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string FormatOf(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".c3d") return "c3d";
  if (ext == ".trc") return "trc";
  if (ext == ".bvh") return "bvh";
  if (ext == ".textgrid") return "textgrid";
  if (ext == ".eaf") return "eaf";
  if (ext == ".wav") return "wav";
  if (ext == ".h5" || ext == ".hdf5") return "hdf5";
  return "";
}

std::vector<std::string> ReadSentences(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open the sentence list");
  std::vector<std::string> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 byte-order mark
    if (!formats_internal::IsValidUtf8(line))
      throw InvalidInput(path + ":" + std::to_string(number) + ": not UTF-8 text");
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const size_t last = line.find_last_not_of(" \t");
    out.push_back(line.substr(first, last - first + 1));
  }
  if (in.bad()) throw IoError(path, "cannot read the sentence list");
  if (out.empty()) throw InvalidInput(path + ": no sentences (one per line)");
  return out;
}

}  // namespace csw::jobs
