#include "workbench/gui/fit_dialog.h"

#include <QCloseEvent>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QFile>
#include <QFileDialog>
#include <QFileInfo>
#include <QFontDatabase>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QListWidget>
#include <QPlainTextEdit>
#include <QProgressBar>
#include <QPushButton>
#include <QVBoxLayout>
#include <cmath>
#include <set>

#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/model_reports.h"
#include "workbench/jobs/take_selection.h"

namespace csw::gui {

namespace {

// The defaults of the keys most often changed (docs/model-format.md lists every key).
const char* kDefaultConfig = R"({
  "format": "csw-model-config",
  "version": 1,
  "training": {"min_distance_mm": 2.0},
  "face": {"components": 6},
  "hand": {"angle_components": 20, "ridge": 0.0}
}
)";

}  // namespace

FitDialog::FitDialog(LogPanel* log, QWidget* parent) : QDialog(parent), log_(log) {
  setObjectName("fitDialog");
  setWindowTitle(tr("Fit Model"));
  setModal(false);
  runner_ = new JobRunner(QStringLiteral("csw-fit"), this);

  auto* form = new QFormLayout(this);
  corpus_label_ = new QLabel(tr("(no corpus open)"), this);
  corpus_label_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  form->addRow(tr("Corpus:"), corpus_label_);

  kind_ = new QComboBox(this);
  kind_->setObjectName("fitKind");
  kind_->addItem(tr("face (head motion + facial shape)"), QStringLiteral("face"));
  kind_->addItem(tr("hand (forearm motion + hand shape)"), QStringLiteral("hand"));
  kind_->addItem(tr("rigid (head and forearm clusters)"), QStringLiteral("rigid"));
  form->addRow(tr("Model:"), kind_);

  takes_ = new QListWidget(this);
  takes_->setObjectName("fitTakes");
  takes_->setMinimumHeight(110);
  auto* all = new QPushButton(tr("All"), this);
  auto* none = new QPushButton(tr("None"), this);
  auto* take_buttons = new QHBoxLayout();
  take_buttons->addWidget(all);
  take_buttons->addWidget(none);
  take_buttons->addStretch(1);
  auto* take_box = new QVBoxLayout();
  take_box->addWidget(takes_, 1);
  take_box->addLayout(take_buttons);
  form->addRow(tr("Training takes:"), take_box);

  config_ = new QPlainTextEdit(this);
  config_->setObjectName("fitConfig");
  config_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  config_->setMinimumHeight(120);
  config_->setPlainText(kDefaultConfig);
  config_source_ = new QLabel(tr("defaults (edit, or load a file)"), this);
  auto* load = new QPushButton(tr("Load…"), this);
  auto* defaults = new QPushButton(tr("Defaults"), this);
  auto* config_buttons = new QHBoxLayout();
  config_buttons->addWidget(config_source_, 1);
  config_buttons->addWidget(load);
  config_buttons->addWidget(defaults);
  auto* config_box = new QVBoxLayout();
  config_box->addWidget(config_, 1);
  config_box->addLayout(config_buttons);
  form->addRow(tr("Configuration:"), config_box);

  markerset_ = new QLineEdit(this);
  markerset_->setPlaceholderText(tr("the one the corpus remembers"));
  auto* set_browse = new QPushButton(tr("…"), this);
  auto* set_row = new QHBoxLayout();
  set_row->addWidget(markerset_);
  set_row->addWidget(set_browse);
  form->addRow(tr("Marker set:"), set_row);

  output_ = new QLineEdit(this);
  output_->setObjectName("fitOutput");
  auto* out_browse = new QPushButton(tr("…"), this);
  auto* out_row = new QHBoxLayout();
  out_row->addWidget(output_);
  out_row->addWidget(out_browse);
  form->addRow(tr("Model file:"), out_row);

  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setValue(0);
  progress_->setFormat(QStringLiteral("%p%"));
  form->addRow(tr("Progress:"), progress_);
  status_ = new QLabel(tr("Ready."), this);
  status_->setObjectName("fitStatus");
  status_->setWordWrap(true);
  form->addRow(QString(), status_);

  auto* buttons = new QDialogButtonBox(this);
  fit_button_ = buttons->addButton(tr("Fit"), QDialogButtonBox::AcceptRole);
  fit_button_->setObjectName("fitButton");
  cancel_button_ = buttons->addButton(tr("Cancel Fit"), QDialogButtonBox::ActionRole);
  cancel_button_->setObjectName("fitCancelButton");
  cancel_button_->setEnabled(false);
  close_button_ = buttons->addButton(QDialogButtonBox::Close);
  form->addRow(buttons);

  connect(all, &QPushButton::clicked, this, [this] {
    for (int i = 0; i < takes_->count(); ++i) takes_->item(i)->setCheckState(Qt::Checked);
  });
  connect(none, &QPushButton::clicked, this, [this] {
    for (int i = 0; i < takes_->count(); ++i) takes_->item(i)->setCheckState(Qt::Unchecked);
  });
  connect(load, &QPushButton::clicked, this, [this] {
    const QString p = QFileDialog::getOpenFileName(this, tr("Load Model Configuration"), config_file_,
                                                   tr("Model configuration (*.json);;All files (*)"));
    if (!p.isEmpty()) LoadConfigFile(p);
  });
  connect(defaults, &QPushButton::clicked, this, [this] { SetConfigText(kDefaultConfig); });
  connect(config_, &QPlainTextEdit::textChanged, this, [this] {
    if (config_file_.isEmpty()) return;
    config_source_->setText(config_->toPlainText() == config_file_text_
                                ? tr("from %1").arg(QFileInfo(config_file_).fileName())
                                : tr("edited from %1").arg(QFileInfo(config_file_).fileName()));
  });
  connect(set_browse, &QPushButton::clicked, this, [this] {
    const QString p =
        QFileDialog::getOpenFileName(this, tr("Marker set"), markerset_->text(), tr("Marker set (*.json)"));
    if (!p.isEmpty()) markerset_->setText(p);
  });
  connect(out_browse, &QPushButton::clicked, this, [this] {
    const QString p = QFileDialog::getSaveFileName(this, tr("Model file"), output_->text(), tr("csw model file (*.h5)"),
                                                   nullptr, QFileDialog::DontConfirmOverwrite);
    if (!p.isEmpty()) output_->setText(p);
  });
  connect(fit_button_, &QPushButton::clicked, this, [this] { StartFit(); });
  connect(cancel_button_, &QPushButton::clicked, this, &FitDialog::CancelFit);
  connect(close_button_, &QPushButton::clicked, this, &QDialog::close);

  connect(runner_, &JobRunner::ProgressChanged, this, [this](const QString& stage, double fraction) {
    progress_->setValue(static_cast<int>(std::lround(fraction * 1000)));
    status_->setText(tr("Fitting: %1").arg(stage));
  });
  connect(runner_, &JobRunner::Succeeded, this, [this] {
    SetRunning(false);
    result_ = pending_;
    const QString out = QString::fromStdString(running_options_.output);
    progress_->setValue(1000);
    status_->setText(
        tr("Saved the %1 model to %2.").arg(QString::fromStdString(running_options_.kind), QFileInfo(out).fileName()));
    Log(0, QString::fromStdString(jobs::FitText(result_)).trimmed());
    emit ModelSaved(out);
    emit FitFinished(QStringLiteral("succeeded"));
  });
  connect(runner_, &JobRunner::Canceled, this, [this] {
    SetRunning(false);
    progress_->setValue(0);
    const QString m = tr("Fit cancelled: %1 was left unchanged.").arg(QString::fromStdString(running_options_.output));
    status_->setText(m);
    Log(0, m);
    emit FitFinished(QStringLiteral("canceled"));
  });
  connect(runner_, &JobRunner::Failed, this, [this](const QString& message) {
    SetRunning(false);
    progress_->setValue(0);
    status_->setText(tr("Fit failed: %1").arg(message));
    Log(2, tr("Fit failed: %1").arg(message));
    emit FitFinished(QStringLiteral("failed"));
  });
  resize(620, 640);
}

FitDialog::~FitDialog() = default;

void FitDialog::Log(int level, const QString& message) {
  if (log_ == nullptr) return;
  log_->Add(level == 0   ? LogPanel::Level::kInfo
            : level == 1 ? LogPanel::Level::kWarning
                         : LogPanel::Level::kError,
            message);
}

void FitDialog::SetCorpus(const QString& corpus, const QStringList& takes) {
  corpus_ = corpus;
  corpus_label_->setText(corpus.isEmpty() ? tr("(no corpus open)") : corpus);
  std::set<std::string> names;
  for (const QString& t : takes) names.insert(t.toStdString());
  takes_->clear();
  for (const QString& t : takes) {
    auto* item = new QListWidgetItem(t, takes_);
    item->setFlags(item->flags() | Qt::ItemIsUserCheckable);
    item->setCheckState(jobs::IsGeneratedFillVersion(t.toStdString(), names) ? Qt::Unchecked : Qt::Checked);
  }
  if (output_->text().isEmpty() && !corpus.isEmpty()) {
    const QFileInfo info(corpus);
    output_->setText(info.absoluteDir().filePath(info.completeBaseName() + QStringLiteral(".models.h5")));
  }
}

void FitDialog::SetKind(const QString& kind) {
  const int i = kind_->findData(kind);
  if (i >= 0) kind_->setCurrentIndex(i);
}

void FitDialog::SetOutput(const QString& model_file) { output_->setText(model_file); }

void FitDialog::SetMarkerSetFile(const QString& path) { markerset_->setText(path); }

void FitDialog::SetCheckedTakes(const QStringList& takes) {
  for (int i = 0; i < takes_->count(); ++i)
    takes_->item(i)->setCheckState(takes.contains(takes_->item(i)->text()) ? Qt::Checked : Qt::Unchecked);
}

QStringList FitDialog::CheckedTakes() const {
  QStringList out;
  for (int i = 0; i < takes_->count(); ++i)
    if (takes_->item(i)->checkState() == Qt::Checked) out << takes_->item(i)->text();
  return out;
}

void FitDialog::SetConfigText(const QString& json) {
  config_file_.clear();
  config_file_text_.clear();
  config_->setPlainText(json);
  config_source_->setText(tr("edited here"));
}

QString FitDialog::ConfigText() const { return config_->toPlainText(); }

bool FitDialog::LoadConfigFile(const QString& path) {
  QFile f(path);
  if (!f.open(QIODevice::ReadOnly | QIODevice::Text)) {
    status_->setText(tr("Cannot read %1: %2").arg(path, f.errorString()));
    return false;
  }
  config_file_text_ = QString::fromUtf8(f.readAll());
  config_file_ = QFileInfo(path).absoluteFilePath();
  config_->setPlainText(config_file_text_);
  config_source_->setText(tr("from %1").arg(QFileInfo(path).fileName()));
  return true;
}

jobs::FitOptions FitDialog::Options(QString* why) {
  jobs::FitOptions o;
  why->clear();
  o.corpus = corpus_.toStdString();
  o.kind = kind_->currentData().toString().toStdString();
  o.output = output_->text().trimmed().toStdString();
  o.markerset = markerset_->text().trimmed().toStdString();
  const QStringList checked = CheckedTakes();
  if (checked.isEmpty()) {
    *why = tr("no training take checked");
    return o;
  }
  // All the default ones checked = the default selection (as `csw fit` without --takes).
  bool default_selection = true;
  std::set<std::string> names;
  for (int i = 0; i < takes_->count(); ++i) names.insert(takes_->item(i)->text().toStdString());
  for (int i = 0; i < takes_->count(); ++i) {
    const bool fill = jobs::IsGeneratedFillVersion(takes_->item(i)->text().toStdString(), names);
    if ((takes_->item(i)->checkState() == Qt::Checked) == fill) default_selection = false;
  }
  if (!default_selection) {
    for (const QString& t : checked) o.takes.push_back(jobs::EscapeTakeName(t.toStdString()));
  }
  const QString text = config_->toPlainText();
  if (!config_file_.isEmpty() && text == config_file_text_) {
    o.config = config_file_.toStdString();
  } else if (!text.trimmed().isEmpty()) {
    try {
      jobs::ParseModelConfig(text.toStdString(), "the configuration");
    } catch (const std::exception& e) {
      *why = QString::fromStdString(e.what());
      return o;
    }
    if (!temp_) temp_ = std::make_unique<QTemporaryDir>();
    if (!temp_->isValid()) {
      *why = tr("cannot make a temporary folder for the configuration");
      return o;
    }
    const QString p = temp_->filePath(QStringLiteral("fit-config.json"));
    QFile f(p);
    if (!f.open(QIODevice::WriteOnly | QIODevice::Truncate) || f.write(text.toUtf8()) < 0 || !f.flush()) {
      *why = tr("cannot write %1: %2").arg(p, f.errorString());
      return o;
    }
    o.config = p.toStdString();
  }
  if (const std::string c = o.Check(); !c.empty()) *why = QString::fromStdString(c);
  return o;
}

bool FitDialog::StartFit() {
  if (runner_->running()) {
    status_->setText(tr("A fit is already running."));
    return false;
  }
  QString why;
  jobs::FitOptions options = Options(&why);
  if (!why.isEmpty()) {
    status_->setText(tr("Not started: %1").arg(why));
    Log(2, tr("Fit not started: %1").arg(why));
    return false;
  }
  running_options_ = options;
  pending_ = nlohmann::json();
  if (!runner_->Start([this, options](Progress& progress) { pending_ = jobs::Fit(options, progress); })) return false;
  SetRunning(true);
  progress_->setValue(0);
  status_->setText(tr("Fitting the %1 model…").arg(QString::fromStdString(options.kind)));
  Log(0, tr("Fitting the %1 model on %2 into %3…")
             .arg(QString::fromStdString(options.kind), corpus_, QString::fromStdString(options.output)));
  return true;
}

void FitDialog::CancelFit() {
  if (!runner_->running()) return;
  status_->setText(tr("Cancelling…"));
  runner_->Cancel();
}

bool FitDialog::running() const { return runner_->running(); }

void FitDialog::SetRunning(bool on) {
  fit_button_->setEnabled(!on);
  cancel_button_->setEnabled(on);
  kind_->setEnabled(!on);
  takes_->setEnabled(!on);
  config_->setReadOnly(on);
  output_->setEnabled(!on);
  markerset_->setEnabled(!on);
}

void FitDialog::closeEvent(QCloseEvent* event) {
  // Closing hides the dialog; a running fit goes on (its progress is in the
  // log when it ends). The window cancels it when it closes.
  event->accept();
}

}  // namespace csw::gui
