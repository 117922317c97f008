#include "io/corpus/corpus_tools.h"

#include <unistd.h>

#include <filesystem>
#include <system_error>
#include <vector>

#include "core/error.h"
#include "core/file_util.h"
#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "io/corpus/hdf5_util.h"

#ifndef CSW_VERSION
#define CSW_VERSION "unknown"
#endif

namespace csw {
namespace {

namespace fs = std::filesystem;
using h5::Handle;
using h5::Where;

Handle FileAccess(const Where& where) {
  Handle fapl = h5::Own(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, where, "cannot create file access properties", "");
  h5::Check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), where, "cannot set file format bounds",
            "");
  h5::Check(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_SEMI), where, "cannot set close degree", "");
  return fapl;
}

// True when every take of the corpus lives in its own files (external links).
bool IsSplit(const std::string& path) {
  Where where{path};
  Handle fapl = FileAccess(where);
  Handle f = h5::Own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose, where, "cannot open", path);
  if (h5::ReadAttrInt(f.get(), "format_version", where, "/").value_or(1) < 2) return false;
  Handle takes = h5::OpenGroup(f.get(), "takes", where, "/takes");
  for (const std::string& name : h5::LinkNames(takes.get(), where, "/takes")) {
    Handle g = h5::OpenGroup(takes.get(), name, where, "/takes/" + name);
    for (const std::string& member : h5::LinkNames(g.get(), where, "/takes/" + name)) {
      H5L_info_t info;
      if (H5Lget_info(g.get(), member.c_str(), &info, H5P_DEFAULT) < 0 || info.type != H5L_TYPE_EXTERNAL) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
  }
  return true;
}

}  // namespace

void PackCorpus(const std::string& path, const std::string& out_path, Progress& progress) {
  std::error_code ec;
  if (fs::exists(out_path, ec)) {
    throw IoError(out_path, fs::equivalent(path, out_path, ec) ? "is the corpus itself; pack into a new file"
                                                               : "already exists; not replacing it");
  }
  // Keeps the corpus' files from being collected while they are copied.
  Corpus corpus = Corpus::Open(path);
  const std::vector<TakeSummary> summaries = corpus.Takes();
  auto lock = h5::Lock();
  const Where where{out_path};
  const std::string temp = HiddenSibling(out_path, ".csw-tmp");
  struct Cleanup {
    std::string file;
    bool keep = false;
    ~Cleanup() {
      if (!keep) ::unlink(file.c_str());
    }
  } cleanup{temp};
  ::unlink(temp.c_str());
  {
    const Where src_where{path};
    Handle fapl = FileAccess(src_where);
    Handle src = h5::Own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose, src_where, "cannot open", path);
    Handle out_fapl = FileAccess(where);
    Handle dst = h5::Own(H5Fcreate(temp.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, out_fapl.get()), H5Fclose, where,
                         "cannot create", temp);
    h5::WriteAttr(dst.get(), "format", std::string("csw-corpus"), where, "/");
    h5::WriteAttr(dst.get(), "format_version", int64_t{kCorpusFormatVersion}, where, "/");
    h5::WriteAttr(dst.get(), "csw_version", std::string(CSW_VERSION), where, "/");
    h5::WriteAttr(dst.get(), "layout", std::string("packed"), where, "/");
    Handle src_takes = h5::OpenGroup(src.get(), "takes", src_where, "/takes");
    Handle dst_takes = h5::CreateGroup(dst.get(), "takes", where, "/takes");
    for (size_t i = 0; i < summaries.size(); ++i) {
      progress.Update("packing", static_cast<double>(i) / static_cast<double>(summaries.size()));
      const std::string& name = summaries[i].name;
      // Member by member, following the external links (CopyTree), so that
      // the pack holds the data itself.
      h5::CopyTree(src_takes.get(), name, dst_takes.get(), where, "/takes/" + name);
    }
    for (const char* reserved : {"models", "dictionaries"}) {
      if (h5::LinkExists(src.get(), reserved)) {
        h5::CopyTree(src.get(), reserved, dst.get(), where, std::string("/") + reserved);
      } else {
        h5::CreateGroup(dst.get(), reserved, where, std::string("/") + reserved);
      }
    }
    src_takes.Reset();
    dst_takes.Reset();
    h5::Check(H5Fflush(dst.get(), H5F_SCOPE_GLOBAL), where, "cannot flush", temp);
    if (!dst.Reset()) throw IoError(out_path, "cannot close " + temp + ": " + h5::TakeErrorMessage());
  }
  progress.Update("packing", 1.0);
  ReplaceFileDurably(temp, out_path);
  cleanup.keep = true;
}

bool UpgradeCorpus(const std::string& path, Progress& progress) {
  Corpus::Open(path);  // one clear error when it is not a corpus
  {
    auto lock = h5::Lock();
    if (IsSplit(path)) return false;
  }
  CorpusTransaction tx(path, progress);
  tx.Commit();
  return true;
}

}  // namespace csw
