#include "workbench/gui/job_dialog.h"

#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QPlainTextEdit>
#include <QProgressBar>
#include <QPushButton>
#include <QRegularExpression>
#include <QToolButton>
#include <QVBoxLayout>
#include <cmath>

#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/jobs/clean_job.h"
#include "workbench/jobs/cue_job.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/keys_suggest_job.h"
#include "workbench/jobs/phasing_job.h"

namespace csw::gui {

namespace {

std::string Str(const JobValues& v, const char* key) {
  auto it = v.find(QString::fromLatin1(key));
  return it == v.end() ? std::string() : it->second.trimmed().toStdString();
}

std::vector<std::string> Takes(const JobValues& v) {
  auto it = v.find(QStringLiteral("takes"));
  return it == v.end() ? std::vector<std::string>() : SplitTakes(it->second);
}

// A number typed in a field; *why says which field when it is not one.
double Number(const JobValues& v, const char* key, std::string* why) {
  bool ok = false;
  const double x = QString::fromStdString(Str(v, key)).toDouble(&ok);
  if ((!ok || !std::isfinite(x)) && why->empty()) *why = std::string(key) + " must be a number";
  return x;
}

JobField Text(const char* key, const QString& label, const QString& value, const QString& help, bool required = false) {
  return {QString::fromLatin1(key), label, JobField::Kind::kText, value, help, required};
}
JobField Open(const char* key, const QString& label, const QString& help, bool required) {
  return {QString::fromLatin1(key), label, JobField::Kind::kOpenFile, QString(), help, required};
}
JobField Save(const char* key, const QString& label, const QString& help, bool required) {
  return {QString::fromLatin1(key), label, JobField::Kind::kSaveFile, QString(), help, required};
}

JobField MarkerSet() {
  return {QStringLiteral("markerset"),
          QObject::tr("Marker set (JSON)"),
          JobField::Kind::kOpenFile,
          QString(),
          QObject::tr("Empty = the marker set the corpus remembers for each take (File > Load Marker Set fills it)"),
          false};
}

const QString kTakesHelp = QObject::tr(
    "Take names or patterns (take_selection: e.g. s01*, -s01_03), separated by "
    "commas or spaces; empty = every take but generated fill versions");

// ---- the jobs' options from the field values (the CLI's defaults) ----------

jobs::CueOptions CueOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::CueOptions o;
  o.input = corpus;
  o.takes = Takes(v);
  o.phones = Str(v, "phones");
  o.symbols = Str(v, "symbols");
  o.tier = Str(v, "tier");
  return o;
}

jobs::KeysSuggestOptions SuggestOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::KeysSuggestOptions o;
  o.corpus = corpus;
  o.takes = Takes(v);
  o.phones = Str(v, "phones");
  o.phasing = Str(v, "phasing");
  o.tier = Str(v, "tier");
  o.placement_tier = Str(v, "placement_tier");
  o.markerset = Str(v, "markerset");
  return o;
}

jobs::KeysTrainOptions TrainOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::KeysTrainOptions o;
  o.corpus = corpus;
  o.takes = Takes(v);
  o.tier = Str(v, "tier");
  o.placement_tier = Str(v, "placement_tier");
  o.output = Str(v, "output");
  o.markerset = Str(v, "markerset");
  return o;
}

jobs::KeysScoreOptions ScoreOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::KeysScoreOptions o;
  o.corpus = corpus;
  o.keys = Str(v, "keys");
  o.takes = Takes(v);
  o.tier = Str(v, "tier");
  o.placement_tier = Str(v, "placement_tier");
  o.figures = Str(v, "figures");
  o.markerset = Str(v, "markerset");
  return o;
}

jobs::PhasingOptions PhasingOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::PhasingOptions o;
  o.corpus = corpus;
  o.keys = Str(v, "keys");
  o.takes = Takes(v);
  o.phones = Str(v, "phones");
  o.targets = Str(v, "targets");
  o.csv = Str(v, "csv");
  o.figures = Str(v, "figures");
  o.markerset = Str(v, "markerset");
  return o;
}

jobs::CleanOptions CleanOptionsOf(const std::string& corpus, const JobValues& v, std::string* why) {
  jobs::CleanOptions o;
  o.corpus = corpus;
  o.takes = Takes(v);
  for (const QString& m :
       QString::fromStdString(Str(v, "fill")).split(QRegularExpression(QStringLiteral("[,\\s]+")), Qt::SkipEmptyParts))
    o.fill.push_back(m.toStdString());
  o.max_gap_s = Number(v, "max_gap_s", why);
  o.filter = Str(v, "filter");
  o.cutoff_hz = Number(v, "cutoff_hz", why);
  o.models = Str(v, "models");
  o.markerset = Str(v, "markerset");
  return o;
}

jobs::DictBuildOptions DictOptionsOf(const std::string& corpus, const JobValues& v) {
  jobs::DictBuildOptions o;
  o.corpus = corpus;
  o.models = Str(v, "models");
  o.keys = Str(v, "keys");
  o.output = Str(v, "output");
  o.takes = Takes(v);
  o.tier = Str(v, "tier");
  o.phones = Str(v, "phones");
  return o;
}

std::vector<JobSpec> MakeJobs() {
  std::vector<JobSpec> specs;
  {
    JobSpec s;
    s.id = QStringLiteral("cue");
    s.title = QObject::tr("Derive Expected Keys (csw cue)");
    s.help = QObject::tr(
        "Applies the LfPC rules to each take's phone tier and writes the expected keys as an "
        "interval tier (docs/phonetics.md).");
    s.fields = {Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
                Text("phones", QObject::tr("Phone tier"), QStringLiteral("phones"), QObject::tr("The phone tier read")),
                Text("symbols", QObject::tr("Phone symbols"), QStringLiteral("auto"),
                     QObject::tr("auto, ipa (or mfa), xsampa, sppas")),
                Text("tier", QObject::tr("Tier written"), QStringLiteral("expected_keys"), QString(), true)};
    s.writes_corpus = true;
    s.run = [](const std::string& c, const JobValues& v, Progress& p) { return jobs::Cue(CueOptionsOf(c, v), p); };
    s.text = [](const nlohmann::json& r) { return jobs::CueText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return CueOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("keys-suggest");
    s.title = QObject::tr("Suggest Target Frames (csw keys suggest)");
    s.help = QObject::tr(
        "Proposes a target frame for every expected key (the hand-speed minimum nearest its "
        "expected time) as point tiers, so labelling confirms rather than hunts.");
    s.fields = {Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
                Text("phones", QObject::tr("Phone tier"), QStringLiteral("phones"), QString()),
                Open("phasing", QObject::tr("Phasing model (JSON)"), QObject::tr("Empty = Attina's means"), false),
                Text("tier", QObject::tr("Shape targets tier"), QStringLiteral("keys_suggested"), QString(), true),
                Text("placement_tier", QObject::tr("Placement targets tier"), QStringLiteral("placement_suggested"),
                     QString(), true),
                MarkerSet()};
    s.writes_corpus = true;
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      return jobs::KeysSuggest(SuggestOptionsOf(c, v), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::KeysSuggestText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return SuggestOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("keys-train");
    s.title = QObject::tr("Train Key Recogniser (csw keys train)");
    s.help = QObject::tr(
        "One Gaussian per hand shape and per placement from the labelled target frames; written "
        "into a model file (other models in it are kept).");
    s.fields = {Text("takes", QObject::tr("Takes"), QString(), kTakesHelp, true),
                Text("tier", QObject::tr("Label tier"), QStringLiteral("keys"), QString(), true),
                Text("placement_tier", QObject::tr("Placement label tier"), QStringLiteral("placement_targets"),
                     QObject::tr("Used when the take has it")),
                Save("output", QObject::tr("Model file"), QObject::tr("Created or updated"), true), MarkerSet()};
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      return jobs::KeysTrain(TrainOptionsOf(c, v), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::KeysTrainText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return TrainOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("keys-score");
    s.title = QObject::tr("Score Keys (csw keys score)");
    s.help = QObject::tr(
        "The gestural score (posteriors), the free decoding and the gesture extents of each take, "
        "written as tiers and a score set; accuracies against the label tier when present.");
    s.fields = {
        Open("keys", QObject::tr("Key model file"), QObject::tr("A model file with a /keys group"), true),
        Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
        Text("tier", QObject::tr("Label tier"), QStringLiteral("keys"), QString()),
        Text("placement_tier", QObject::tr("Placement label tier"), QStringLiteral("placement_targets"), QString()),
        Text("figures", QObject::tr("Figures folder"), QString(),
             QObject::tr("Confusion matrices as PNG; empty = none")),
        MarkerSet()};
    s.writes_corpus = true;
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      return jobs::KeysScore(ScoreOptionsOf(c, v), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::KeysScoreText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return ScoreOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("phasing");
    s.title = QObject::tr("Measure Phasing (csw phasing)");
    s.help = QObject::tr(
        "Onset and target times of every key's shape and placement gestures against its "
        "syllable's acoustic landmarks, kinematic and posterior (docs/analysis.md).");
    s.fields = {
        Open("keys", QObject::tr("Key model file"), QString(), true),
        Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
        Text("phones", QObject::tr("Phone tier"), QStringLiteral("phones"), QString()),
        Text("targets", QObject::tr("Rough targets"), QStringLiteral("auto"), QObject::tr("labels, aligned or auto")),
        Save("csv", QObject::tr("Per-key CSV"), QObject::tr("Empty = none"), false),
        Text("figures", QObject::tr("Figures folder"), QString(), QObject::tr("Empty = none")),
        MarkerSet()};
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      return jobs::Phasing(PhasingOptionsOf(c, v), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::PhasingText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return PhasingOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("clean");
    s.title = QObject::tr("Clean Takes (csw clean)");
    s.help = QObject::tr(
        "Gap report, gap filling (spline, rigid, pattern, dct, model) and filtering; the cleaned "
        "takes are written as new versions (docs/cleaning.md).");
    s.fields = {Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
                Text("fill", QObject::tr("Fill methods"), QStringLiteral("spline, rigid"),
                     QObject::tr("In order; empty = report only")),
                Text("max_gap_s", QObject::tr("Longest gap filled (s)"), QStringLiteral("0.5"), QString(), true),
                Open("models", QObject::tr("Models (model fill)"), QString(), false),
                Text("filter", QObject::tr("Filter"), QString(), QObject::tr("Empty, butterworth or kalman")),
                Text("cutoff_hz", QObject::tr("Cut-off (Hz)"), QStringLiteral("15"), QString(), true),
                MarkerSet()};
    s.writes_corpus = true;
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      std::string why;
      return jobs::Clean(CleanOptionsOf(c, v, &why), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::CleanText(r); };
    s.check = [](const std::string& c, const JobValues& v) {
      std::string why;
      jobs::CleanOptions o = CleanOptionsOf(c, v, &why);
      return why.empty() ? o.Check() : why;
    };
    specs.push_back(std::move(s));
  }
  {
    JobSpec s;
    s.id = QStringLiteral("dict-build");
    s.title = QObject::tr("Build Dictionaries (csw dict build)");
    s.help = QObject::tr(
        "The dikey and diphone dictionaries of the synthesizer from the aligned key tiers, with "
        "the models' fingerprint and a coverage report (docs/dictionary-format.md).");
    s.fields = {Open("models", QObject::tr("Models file"), QObject::tr("Face and hand models (csw fit)"), true),
                Open("keys", QObject::tr("Key model file"), QObject::tr("Optional: recorded and checked"), false),
                Save("output", QObject::tr("Dictionary file"), QObject::tr("Replaced"), true),
                Text("takes", QObject::tr("Takes"), QString(), kTakesHelp),
                Text("tier", QObject::tr("Key tier"), QStringLiteral("keys_aligned"), QString(), true),
                Text("phones", QObject::tr("Phone tier"), QStringLiteral("phones"), QString())};
    s.run = [](const std::string& c, const JobValues& v, Progress& p) {
      return jobs::DictBuild(DictOptionsOf(c, v), p);
    };
    s.text = [](const nlohmann::json& r) { return jobs::DictBuildText(r); };
    s.check = [](const std::string& c, const JobValues& v) { return DictOptionsOf(c, v).Check(); };
    specs.push_back(std::move(s));
  }
  return specs;
}

}  // namespace

const std::vector<JobSpec>& AnalysisJobs() {
  static const std::vector<JobSpec> specs = MakeJobs();
  return specs;
}

const JobSpec* FindAnalysisJob(const QString& id) {
  for (const JobSpec& s : AnalysisJobs())
    if (s.id == id) return &s;
  return nullptr;
}

std::vector<std::string> SplitTakes(const QString& text) {
  std::vector<std::string> out;
  for (const QString& t : text.split(QRegularExpression(QStringLiteral("[,\\s]+")), Qt::SkipEmptyParts))
    out.push_back(t.toStdString());
  return out;
}

JobDialog::JobDialog(const JobSpec& spec, LogPanel* log, QWidget* parent) : QDialog(parent), spec_(spec), log_(log) {
  setObjectName(QStringLiteral("jobDialog-") + spec_.id);
  setWindowTitle(spec_.title);
  setModal(false);
  runner_ = new JobRunner(QStringLiteral("csw-") + spec_.id, this);

  auto* layout = new QVBoxLayout(this);
  auto* help = new QLabel(spec_.help, this);
  help->setWordWrap(true);
  layout->addWidget(help);
  auto* form = new QFormLayout();
  corpus_label_ = new QLabel(tr("(no corpus open)"), this);
  form->addRow(tr("Corpus:"), corpus_label_);
  for (const JobField& f : spec_.fields) {
    auto* edit = new QLineEdit(f.value, this);
    edit->setObjectName(f.key);
    edit->setToolTip(f.help);
    if (f.required) edit->setPlaceholderText(tr("required"));
    fields_[f.key] = edit;
    if (f.kind == JobField::Kind::kText) {
      form->addRow(f.label + QStringLiteral(":"), edit);
      continue;
    }
    auto* row = new QHBoxLayout();
    row->addWidget(edit, 1);
    auto* browse = new QToolButton(this);
    browse->setText(QStringLiteral("…"));
    row->addWidget(browse);
    const bool save = f.kind == JobField::Kind::kSaveFile;
    const QString title = f.label;
    connect(browse, &QToolButton::clicked, this, [this, edit, save, title] {
      const QString dir = QFileInfo(edit->text().isEmpty() ? corpus_ : edit->text()).absolutePath();
      const QString path =
          save ? QFileDialog::getSaveFileName(this, title, dir) : QFileDialog::getOpenFileName(this, title, dir);
      if (!path.isEmpty()) edit->setText(path);
    });
    form->addRow(f.label + QStringLiteral(":"), row);
  }
  layout->addLayout(form);

  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setValue(0);
  layout->addWidget(progress_);
  status_ = new QLabel(this);
  status_->setWordWrap(true);
  layout->addWidget(status_);
  output_ = new QPlainTextEdit(this);
  output_->setReadOnly(true);
  output_->setMinimumHeight(140);
  output_->setLineWrapMode(QPlainTextEdit::NoWrap);
  layout->addWidget(output_, 1);

  auto* buttons = new QHBoxLayout();
  buttons->addStretch(1);
  run_button_ = new QPushButton(tr("Run"), this);
  run_button_->setDefault(true);
  cancel_button_ = new QPushButton(tr("Cancel"), this);
  cancel_button_->setEnabled(false);
  close_button_ = new QPushButton(tr("Close"), this);
  buttons->addWidget(run_button_);
  buttons->addWidget(cancel_button_);
  buttons->addWidget(close_button_);
  layout->addLayout(buttons);
  resize(560, 520);

  connect(run_button_, &QPushButton::clicked, this, [this] { Start(); });
  connect(cancel_button_, &QPushButton::clicked, this, &JobDialog::Cancel);
  connect(close_button_, &QPushButton::clicked, this, &QDialog::close);
  connect(runner_, &JobRunner::ProgressChanged, this, [this](const QString& stage, double fraction) {
    progress_->setValue(static_cast<int>(std::lround(fraction * 1000)));
    status_->setText(tr("Running: %1").arg(stage));
  });
  connect(runner_, &JobRunner::Succeeded, this, [this] {
    SetRunning(false);
    result_ = pending_;
    progress_->setValue(1000);
    const QString text = QString::fromStdString(spec_.text(result_)).trimmed();
    output_->setPlainText(text);
    status_->setText(tr("Done."));
    Log(0, tr("%1 done on %2:\n%3").arg(spec_.title, running_corpus_, text));
    emit JobFinished(QStringLiteral("succeeded"));
    if (spec_.writes_corpus) emit CorpusWritten(running_corpus_);
  });
  connect(runner_, &JobRunner::Canceled, this, [this] {
    SetRunning(false);
    status_->setText(tr("Cancelled: nothing was written."));
    Log(1, tr("%1 cancelled: %2 was left as it was.").arg(spec_.title, running_corpus_));
    emit JobFinished(QStringLiteral("canceled"));
  });
  connect(runner_, &JobRunner::Failed, this, [this](const QString& message) {
    SetRunning(false);
    status_->setText(tr("Failed: %1").arg(message));
    Log(2, tr("%1 failed: %2").arg(spec_.title, message));
    emit JobFinished(QStringLiteral("failed"));
  });
}

JobDialog::~JobDialog() = default;

void JobDialog::SetCorpus(const QString& corpus) {
  corpus_ = corpus;
  corpus_label_->setText(corpus.isEmpty() ? tr("(no corpus open)") : corpus);
}

void JobDialog::SetValue(const QString& key, const QString& value) {
  if (QLineEdit* e = field(key)) e->setText(value);
}

QString JobDialog::Value(const QString& key) const {
  QLineEdit* e = field(key);
  return e ? e->text() : QString();
}

QLineEdit* JobDialog::field(const QString& key) const {
  auto it = fields_.find(key);
  return it == fields_.end() ? nullptr : it->second;
}

JobValues JobDialog::Values() const {
  JobValues v;
  for (const auto& [key, edit] : fields_) v[key] = edit->text();
  return v;
}

bool JobDialog::running() const { return runner_->running(); }

bool JobDialog::Start() {
  if (runner_->running()) {
    status_->setText(tr("The job is already running."));
    return false;
  }
  if (corpus_.isEmpty()) {
    status_->setText(tr("Open a corpus first."));
    return false;
  }
  const JobValues values = Values();
  for (const JobField& f : spec_.fields) {
    if (f.required && values.at(f.key).trimmed().isEmpty()) {
      status_->setText(tr("%1 is required.").arg(f.label));
      return false;
    }
  }
  const std::string corpus = corpus_.toStdString();
  if (std::string why = spec_.check(corpus, values); !why.empty()) {
    status_->setText(tr("Not started: %1").arg(QString::fromStdString(why)));
    return false;
  }
  pending_ = nlohmann::json();
  const JobSpec::RunFn run = spec_.run;
  if (!runner_->Start([this, run, corpus, values](Progress& progress) { pending_ = run(corpus, values, progress); }))
    return false;
  running_corpus_ = corpus_;
  SetRunning(true);
  progress_->setValue(0);
  output_->clear();
  status_->setText(tr("Running…"));
  Log(0, tr("%1 started on %2…").arg(spec_.title, corpus_));
  return true;
}

void JobDialog::Cancel() {
  if (!runner_->running()) return;
  status_->setText(tr("Cancelling…"));
  runner_->Cancel();
}

void JobDialog::SetRunning(bool on) {
  run_button_->setEnabled(!on);
  cancel_button_->setEnabled(on);
  for (auto& [key, edit] : fields_) edit->setEnabled(!on);
}

void JobDialog::Log(int level, const QString& message) {
  if (log_ == nullptr) return;
  if (level == 0) log_->Info(message);
  if (level == 1) log_->Warning(message);
  if (level == 2) log_->Error(message);
}

}  // namespace csw::gui
