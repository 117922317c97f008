#include "workbench/gui/export_files.h"

#include <unistd.h>

#include <QMessageBox>
#include <QWidget>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>
#include <sstream>

#include "analysis/keys/key_model.h"
#include "core/error.h"
#include "core/file_util.h"
#include "io/dictionary/dictionary_file.h"
#include "io/formats/eaf.h"
#include "io/formats/textgrid.h"
#include "io/models/model_file.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/log_panel.h"
#include "workbench/jobs/inspect_job.h"

namespace csw::gui {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string TempFor(const std::string& path) {
  static std::atomic<int> counter{0};
  return HiddenSibling(path, ".csw-tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++));
}

// Writes through `write(temp)` and renames the result over `path`.
template <typename Write>
void WriteReplacing(const std::string& path, Write write) {
  const std::string temp = TempFor(path);
  try {
    write(temp);
    ReplaceFileDurably(temp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
}

json ClassesJson(const keys::GaussianClassifier& g) {
  json a = json::array();
  for (const auto& c : g.classes()) a.push_back({{"label", c.label}, {"count", c.count}});
  return a;
}

std::string ClassesText(const json& classes) {
  std::string s;
  for (const json& c : classes)
    s += (s.empty() ? "" : " ") + std::to_string(c["label"].get<int>()) + " (" +
         std::to_string(c["count"].get<int64_t>()) + ")";
  return s.empty() ? "-" : s;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "-" : s;
}

}  // namespace

std::vector<LabelTier> TiersToExport(const Take& take, const LabelSession* labels, const std::string& corpus) {
  std::vector<LabelTier> tiers = take.tiers;
  if (labels == nullptr) return tiers;
  if (auto known = labels->KnownTiers(corpus, take.name)) tiers = std::move(*known);
  if (labels->has_take() && labels->take_name() == take.name) {
    const LabelTier& now = labels->model()->tier();
    bool replaced = false;
    for (LabelTier& t : tiers)
      if (t.name == now.name) {
        t = now;
        replaced = true;
      }
    if (!replaced && !now.labels.empty()) tiers.push_back(now);
  }
  return tiers;
}

void WriteLabelFile(const std::string& path, const std::vector<LabelTier>& tiers, double xmin, double xmax) {
  const std::string ext = Lower(fs::path(path).extension().string());
  if (ext == ".textgrid") {
    std::vector<LabelTier> filled;
    for (const LabelTier& t : tiers) filled.push_back(FillIntervalGaps(t));
    WriteReplacing(path, [&](const std::string& temp) { WriteTextGrid(temp, filled, xmin, xmax); });
  } else if (ext == ".eaf") {
    WriteReplacing(path, [&](const std::string& temp) { WriteEaf(temp, tiers); });
  } else {
    throw InvalidInput(path + ": unknown label file type '" + ext + "' (expected .TextGrid or .eaf)");
  }
}

FileSummary SummariseModelFile(const std::string& path) {
  FileSummary s;
  Progress quiet;
  json facts;
  try {
    facts = jobs::Inspect(path, quiet);
  } catch (const InvalidInput& inspect_error) {
    // Not a model file: perhaps a dictionary file.
    dict::Dictionary d;
    try {
      d = LoadDictionaryFile(path);
    } catch (const std::exception&) {
      throw InvalidInput(std::string(inspect_error.what()) + " (nor a csw dictionary file)");
    }
    s.kind = "dictionary";
    s.facts = {{"file", path},
               {"format", "dictionary"},
               {"dikey_units", d.dikeys.size()},
               {"diphone_units", d.diphones.size()},
               {"hand_parameters", d.hand_parameter_names.size()},
               {"face_parameters", d.face_parameter_names.size()},
               {"corpus", d.corpus},
               {"models_file", d.models_file},
               {"keys_file", d.keys_file},
               {"key_tier", d.key_tier},
               {"models_fingerprint", d.models_fingerprint}};
    std::ostringstream o;
    o << "dictionary " << path << "\n"
      << "dikey units: " << d.dikeys.size() << " (" << d.hand_parameter_names.size() << " hand parameters)\n"
      << "diphone units: " << d.diphones.size() << " (" << d.face_parameter_names.size() << " face parameters)\n"
      << "built from corpus: " << (d.corpus.empty() ? "-" : d.corpus) << "\n"
      << "models file: " << (d.models_file.empty() ? "-" : d.models_file) << "\n"
      << "key recogniser: " << (d.keys_file.empty() ? "-" : d.keys_file) << " (tier "
      << (d.key_tier.empty() ? "-" : d.key_tier) << ")\n";
    s.text = o.str();
    return s;
  }
  if (facts.value("format", "") != "models")
    throw InvalidInput(path + ": a " + facts.value("format", std::string("?")) +
                       " file, not a models, key-recogniser or dictionary file");
  std::string text = jobs::InspectText(facts);
  const ModelFile mf = LoadModelFile(path);
  const bool models = facts.value("model_count", 0) > 0;
  if (mf.keys) {
    const keys::KeyModel& k = *mf.keys;
    json keys = {{"shape_classes", ClassesJson(k.shape)},   {"placement_classes", ClassesJson(k.placement)},
                 {"training_takes", k.info.training_takes}, {"training_frames", k.info.training_frames},
                 {"created_utc", k.info.created_utc},       {"csw_version", k.info.csw_version}};
    std::ostringstream o;
    o << "key recogniser:\n"
      << "  shape classes (training frames): " << ClassesText(keys["shape_classes"]) << "\n"
      << "  placement classes (training frames): " << ClassesText(keys["placement_classes"]) << "\n"
      << "  training takes: " << JoinNames(k.info.training_takes) << "\n"
      << "  created: " << k.info.created_utc << " (csw " << k.info.csw_version << ")\n";
    text += o.str();
    facts["key_recogniser"] = keys;
  }
  s.kind = mf.keys ? (models ? "models and key recogniser" : "key recogniser") : "models";
  s.facts = std::move(facts);
  s.text = std::move(text);
  return s;
}

FileSummary CopyModelFile(const std::string& source, const std::string& destination, Progress& progress) {
  std::error_code ec;
  if (!fs::exists(source, ec)) throw IoError(source, "no such file");
  if (fs::exists(destination, ec) && fs::equivalent(source, destination, ec))
    throw InvalidInput(destination + ": is the file being exported");
  progress.Update("reading " + source, 0.0);
  SummariseModelFile(source);  // refuses anything but a models, key-recogniser or dictionary file
  progress.Update("copying to " + destination, 0.5);
  WriteReplacing(destination, [&](const std::string& temp) {
    fs::copy_file(source, temp, fs::copy_options::overwrite_existing, ec);
    if (ec) throw IoError(temp, "cannot copy " + source + ": " + ec.message());
  });
  FileSummary s = SummariseModelFile(destination);  // what the copy holds
  progress.Update("copying to " + destination, 1.0);
  return s;
}

ExportRunner::ExportRunner(LogPanel* log, QWidget* dialog_parent, QObject* parent)
    : QObject(parent),
      log_(log),
      dialog_parent_(dialog_parent),
      runner_(new JobRunner(QStringLiteral("csw-export"), this)) {
  connect(runner_, &JobRunner::Succeeded, this, [this] {
    if (file_export_ && pending_) {
      summary_ = *pending_;
      log_->Info(tr("Exported %1 (%2)").arg(path_, QString::fromStdString(summary_.kind)));
      if (dialog_parent_ != nullptr) {
        if (box_ == nullptr) {
          box_ = new QMessageBox(dialog_parent_);
          box_->setObjectName("exportSummary");
          box_->setIcon(QMessageBox::Information);
          box_->setWindowModality(Qt::NonModal);
        }
        box_->setWindowTitle(tr("Exported %1").arg(QString::fromStdString(summary_.kind)));
        box_->setText(tr("%1 written.").arg(path_));
        box_->setInformativeText(QString::fromStdString(summary_.text));
        box_->show();
      }
    } else {
      log_->Info(tr("Labels exported to %1").arg(path_));
    }
    pending_.reset();
    emit Finished(true, path_, QString());
  });
  auto failed = [this](const QString& message) {
    pending_.reset();
    log_->Error(tr("Export to %1 failed: %2").arg(path_, message));
    emit Finished(false, path_, message);
  };
  connect(runner_, &JobRunner::Failed, this, failed);
  connect(runner_, &JobRunner::Canceled, this, [failed] { failed(QStringLiteral("cancelled")); });
}

bool ExportRunner::running() const { return runner_->running(); }

bool ExportRunner::ExportLabels(const QString& path, std::vector<LabelTier> tiers, double xmin, double xmax) {
  if (running() || path.isEmpty()) return false;
  path_ = path;
  file_export_ = false;
  const std::string p = path.toStdString();
  return runner_->Start([p, tiers = std::move(tiers), xmin, xmax](Progress& progress) {
    progress.Update("writing " + p, 0.0);
    WriteLabelFile(p, tiers, xmin, xmax);
    progress.Update("writing " + p, 1.0);
  });
}

bool ExportRunner::ExportModelFile(const QString& source, const QString& destination) {
  if (running() || source.isEmpty() || destination.isEmpty()) return false;
  path_ = destination;
  file_export_ = true;
  auto out = std::make_shared<FileSummary>();
  pending_ = out;
  const std::string s = source.toStdString(), d = destination.toStdString();
  return runner_->Start([s, d, out](Progress& progress) { *out = CopyModelFile(s, d, progress); });
}

}  // namespace csw::gui
