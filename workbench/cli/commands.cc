#include "workbench/cli/commands.h"

#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "workbench/jobs/clean_job.h"
#include "workbench/jobs/coartic_generate_job.h"
#include "workbench/jobs/cue_job.h"
#include "workbench/jobs/demo_job.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/jobs.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/keys_suggest_job.h"
#include "workbench/jobs/model_jobs.h"
#include "workbench/jobs/ohman_job.h"
#include "workbench/jobs/phasing_job.h"
#include "workbench/jobs/say_job.h"
#include "workbench/jobs/segment_job.h"
#include "workbench/jobs/sign_sequence_job.h"
#include "workbench/jobs/transitions_job.h"
#include "workbench/jobs/video_job.h"

namespace csw::cli {

ProgressPrinter::ProgressPrinter(const bool* quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) == 1) {}

void ProgressPrinter::Print(const std::string& stage, double fraction) {
  if (*quiet_) return;
  if (fraction < 0) fraction = 0;
  if (fraction > 1) fraction = 1;
  if (stage != stage_) {
    if (drawn_ && tty_) std::fputc('\n', stderr);
    stage_ = stage;
    last_tenth_ = -1;
    last_percent_ = -1;
  }
  int percent = static_cast<int>(fraction * 100.0);
  if (tty_) {
    if (percent == last_percent_) return;
    last_percent_ = percent;
    const int width = 40;
    int filled = static_cast<int>(fraction * width);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.resize(width, '.');
    std::fprintf(stderr, "\r%-24.24s [%s] %3d%%", stage.c_str(), bar.c_str(), percent);
    std::fflush(stderr);
    drawn_ = true;
  } else {
    int tenth = percent / 10;
    if (tenth == last_tenth_) return;
    last_tenth_ = tenth;
    std::fprintf(stderr, "%s: %d%%\n", stage.c_str(), tenth * 10);
  }
}

void ProgressPrinter::Done() {
  if (drawn_ && tty_) std::fputc('\n', stderr);
  drawn_ = false;
  stage_.clear();
}

namespace {

void PrintJson(const nlohmann::json& j) { std::cout << j.dump(2) << "\n"; }

class InspectCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("inspect", "Print header facts of a C3D, TRC, TextGrid, EAF, WAV, corpus or model file");
    sub_->add_option("file", file_, "File to inspect")->required();
    sub_->add_flag("--json", json_, "Machine-readable JSON output");
  }
  int Run(Progress& progress) override {
    nlohmann::json facts = jobs::Inspect(file_, progress);
    if (json_)
      PrintJson(facts);
    else
      std::cout << jobs::InspectText(facts);
    return 0;
  }

 private:
  std::string file_;
  bool json_ = false;
};

class ImportCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ =
        app.add_subcommand("import",
                           "Import captures (.c3d, .trc, .bvh) with their labels (.TextGrid, .eaf) and audio (.wav), "
                           "paired by base name, into an HDF5 corpus in one crash-safe step");
    sub_->add_option("files", options_.files, "Files to import")->required();
    sub_->add_option("-o,--output", options_.corpus, "Corpus file (created when absent)")->required();
    sub_->add_option("--markerset", options_.markerset, "Marker-set JSON every take must match");
    sub_->add_flag("--replace", options_.replace, "Replace takes that already exist in the corpus");
    sub_->add_option("--units", options_.units,
                     "Length unit of .bvh files (mm, cm, dm, m, in); default guessed from the skeleton's size, "
                     "with a warning");
    sub_->add_flag("--json", json_, "Print the import summary as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    jobs::ImportResult r = jobs::Import(options_, progress);
    if (json_) {
      PrintJson(jobs::ImportReportJson(options_, r));
    } else {
      std::cerr << jobs::ImportWarningsText(r);
      std::cout << jobs::ImportSummaryText(options_, r);
    }
    return 0;
  }

 private:
  jobs::ImportOptions options_;
  bool json_ = false;
};

class InfoCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("info", "Summarise a corpus: takes, durations, markers, gaps, tiers");
    sub_->add_option("corpus", corpus_, "Corpus file")->required();
    sub_->add_flag("--json", json_, "Machine-readable JSON output");
  }
  int Run(Progress&) override {
    nlohmann::json info = jobs::Info(corpus_);
    if (json_)
      PrintJson(info);
    else
      std::cout << jobs::InfoText(info);
    return 0;
  }

 private:
  std::string corpus_;
  bool json_ = false;
};

class ExportCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("export", "Write one take of a corpus as C3D, TRC, CSV or (a skeleton capture) BVH");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("--take", options_.take, "Take name")->required();
    sub_->add_option("--format", options_.format, "c3d, trc, csv or bvh")
        ->required()
        ->check(CLI::IsMember({"c3d", "trc", "csv", "bvh"}));
    sub_->add_option("--units", options_.units,
                     "BVH only: length unit written (mm, cm, dm, m, in); default the take's imported unit");
    sub_->add_option("-o,--output", options_.output, "Output file")->required();
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    jobs::Export(options_, progress);
    std::cout << "wrote " << options_.output << "\n";
    return 0;
  }

 private:
  jobs::ExportOptions options_;
};

class SimulateCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("simulate",
                              "The virtual cuer: write realistic cued-speech captures (C3D, WAV, TextGrid) with "
                              "ground truth");
    sub_->add_option("corpus", options_.corpus,
                     "shapes, visemes, sentences, or demo (all three; every option below applies to it); signs: "
                     "the virtual signer (docs/signing.md), a corpus signs.h5 and <take>.truth.json")
        ->required()
        ->check(CLI::IsMember({"shapes", "visemes", "sentences", "demo", "signs"}));
    sub_->add_option("-o,--output", options_.output, "Output folder")->required();
    sub_->add_option("--seed", options_.seed, "Random seed: the same seed gives identical files")
        ->capture_default_str();
    sub_->add_option("--count", options_.count, "Number of sentences (0 = all)")->capture_default_str();
    sub_->add_option("--text", options_.texts, "French sentence(s) to cue instead of the shipped list");
    sub_->add_option("--sentences", options_.sentences_file, "File with one French sentence per line");
    sub_->add_option("--noise", options_.noise_mm, "Marker noise sigma in mm")->capture_default_str();
    sub_->add_option("--rate", options_.rate_hz, "Capture rate in Hz")->capture_default_str();
    sub_->add_flag("!--no-occlusions", options_.occlusions, "No camera occlusions (dropped samples: --dropouts)");
    sub_->add_option("--dropouts", options_.dropouts_per_s,
                     "Rate of short dropped-sample runs per marker and second (0 = none)")
        ->capture_default_str();
    sub_->add_flag("--label-swaps", options_.label_swaps, "Add a temporary swap of two hand marker labels per take");
    sub_->add_flag("--clean", options_.clean, "Also write <take>.clean.c3d without capture artefacts");
    sub_->add_option("--layout", options_.layout,
                     "Marker layout: default, or lab2 (another lab's: 28 face/head/throat markers whose 3 throat "
                     "markers follow the head's translation fully and its rotation partly, 43 hand markers with "
                     "2-marker phalanges, other names, a smaller hand; docs/virtual-cuer.md)")
        ->capture_default_str();
    sub_->add_option("--hand-scale", options_.hand_scale,
                     "The cuer's hand size relative to the layout's (0.5-2: every finger segment and marker offset "
                     "scaled)")
        ->capture_default_str();
    sub_->add_option("--speech-rate", options_.speech_rate_wpm,
                     "The cuer's speaking rate in words per minute (espeak-ng, 80-450; cuers slow down, and 80 is "
                     "espeak-ng's slowest: a faster cuer leaves more keys only approached)")
        ->capture_default_str();
    sub_->add_option("--phasing", options_.phasing_file,
                     "Phasing-model JSON (docs/virtual-cuer.md): gesture start/target laws instead of the defaults");
    sub_->add_option("--law", options_.law,
                     "signs: transition duration law, surface (the seed's plane) or simple (its eq. 3)")
        ->check(CLI::IsMember({"surface", "simple"}))
        ->capture_default_str();
    sub_->add_option("--manual-jitter", options_.manual_jitter_s,
                     "signs: also write a tier 'manual', the 'signs' tier with each boundary moved by up to this "
                     "many seconds (0 = none)")
        ->capture_default_str();
    sub_->add_option("--hand-offset", options_.hand_offset_s,
                     "signs: each hand's movements are shifted by up to this many seconds (0 = synchronous hands)")
        ->capture_default_str();
    sub_->add_option("--duration-noise", options_.duration_noise_s,
                     "signs: sd (s) of Gaussian noise added to the duration law (0 = the law exactly)")
        ->capture_default_str();
    sub_->add_option("--naming", options_.naming, "signs: joint names, csw or mixamo")
        ->check(CLI::IsMember({"csw", "mixamo"}))
        ->capture_default_str();
  }
  int Run(Progress& progress) override {
    if (options_.corpus == "signs") {  // the signer's defaults: 100 Hz (the seed's), 0.5 mm noise
      if (sub_->get_option("--rate")->count() == 0) options_.rate_hz = 100.0;
      if (sub_->get_option("--noise")->count() == 0) options_.noise_mm = 0.5;
    }
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    std::vector<std::string> takes = jobs::Simulate(options_, progress);
    std::cout << "wrote " << takes.size() << " take(s) to " << options_.output << "\n";
    return 0;
  }

 private:
  jobs::SimulateJobOptions options_;
};

class FitCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("fit",
                              "Fit a rigid-motion (head/forearm), face or hand model on corpus takes and save it "
                              "into a model file (other models in the file are kept)");
    sub_->add_option("kind", options_.kind, "rigid, face or hand")
        ->required()
        ->check(CLI::IsMember({"rigid", "face", "hand"}));
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    // Commas are split by the job (jobs::SelectTakes), which honours backslash escapes.
    sub_->add_option("--takes,--train", options_.takes,
                     "Training takes, comma-separated: name, name@first:end (frames or percentages, name@:50%), "
                     "or a glob pattern ('sentence_0[1-5]*'); \\ escapes * ? [ ] @ , (docs/cli.md); "
                     "default every take but fill versions");
    sub_->add_option("--markerset", options_.markerset, "Marker-set JSON naming the clusters, face and hand markers");
    sub_->add_option("--config", options_.config, "Model configuration JSON (docs/models.md, \"Configuration file\")");
    sub_->add_option("--figures", options_.figures, "Folder for PNG and SVG figures");
    sub_->add_option("-o,--output", options_.output, "Model file (HDF5)")->required();
    sub_->add_flag("--json", json_, "Print the fit summary as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json s = jobs::Fit(options_, progress);
    if (json_) {
      PrintJson(s);
    } else {
      std::cout << jobs::FitText(s);
    }
    return 0;
  }

 private:
  jobs::FitOptions options_;
  bool json_ = false;
};

class InvertCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("invert",
                              "Estimate the models' parameters frame by frame from the visible markers, "
                              "reconstruct every marker and report the errors; --fill saves each take with "
                              "its gaps filled as a new take <take>.filled");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("--models", options_.models, "Model file from csw fit")->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes, comma-separated: name, name@first:end (frames or percentages, name@50%:), or a glob "
                     "pattern ('h00*'); \\ escapes * ? [ ] @ , (docs/cli.md); default every take but fill versions");
    sub_->add_option("--only", options_.only, "Invert only the face or the hand model")
        ->check(CLI::IsMember({"face", "hand"}));
    sub_->add_flag("--fill", options_.fill, "Write the filled takes into the corpus as new takes");
    sub_->add_option("--hide", options_.hide_fraction,
                     "Hide this fraction of the visible samples at random and report their reconstruction error");
    sub_->add_option("--seed", options_.seed, "Random seed for --hide")->capture_default_str();
    sub_->add_option("--truth", options_.truth,
                     "Folder with <take>.clean.c3d (e.g. from csw simulate --clean): score occluded samples "
                     "and cluster poses against it");
    sub_->add_option("--figures", options_.figures, "Folder for PNG and SVG figures");
    sub_->add_option("--frames-csv", options_.frames_csv,
                     "Write one CSV row per (take, frame, model): visible markers, mean and max visible error, "
                     "solve status, iterations, cold start/retry (columns in docs/models.md)");
    sub_->add_option("--worst-frames", options_.worst_frames,
                     "Frames listed per model in the report's worst_frames (by max visible error)")
        ->capture_default_str();
    sub_->add_flag("!--no-edge-correction", options_.edge_correction,
                   "Reconstruct missing samples from the model alone, without adding the model's misfit "
                   "interpolated from the gap's edges");
    sub_->add_option("--threads", options_.threads, "Takes inverted in parallel (0 = all cores)")
        ->capture_default_str();
    sub_->add_flag("!--no-gaussian-fill", options_.inversion.gaussian_fill,
                   "Hand: reconstruct hidden markers from the shape model, not from the model's Gaussian gap "
                   "filler (the conditional mean given the seen markers)");
    sub_->add_option("--prior", options_.inversion.prior_mm,
                     "Weight (mm per parameter sd) pulling shape parameters towards the mean")
        ->capture_default_str();
    sub_->add_option("--max-iterations", options_.inversion.max_iterations, "Solver iterations per frame")
        ->capture_default_str();
    sub_->add_flag("--json", json_, "Print the error report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json s = jobs::Invert(options_, progress);
    if (json_) {
      PrintJson(s);
    } else {
      std::cout << jobs::InvertText(s);
    }
    return 0;
  }

 private:
  jobs::InvertOptions options_;
  bool json_ = false;
};

class CleanCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("clean",
                              "Clean takes before fitting: detect label swaps and spikes, report the gaps and "
                              "which methods can fill them, fill gaps (spline, rigid, pattern, dct, model), "
                              "filter; the result is a new take <take>.filled (docs/cleaning.md)");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes, comma-separated names or glob patterns ('h00*'); \\ escapes * ? [ ] @ , "
                     "(docs/cli.md); default every take but fill versions");
    sub_->add_option("--markerset", options_.markerset,
                     "Marker-set JSON (clusters and segments for the rigid and pattern fills); default the one "
                     "each take was imported with");
    sub_->add_option("--fill", options_.fill,
                     "Fill methods, tried in this order for each gap: spline,rigid,pattern,dct,model "
                     "(default: report only)");
    sub_->add_option("--max-gap", options_.max_gap_s, "Longest gap filled, in seconds (0 = no limit)")
        ->capture_default_str();
    sub_->add_option("--spline", options_.spline, "Spline: smoothing (GCV), cubic or quintic")
        ->check(CLI::IsMember({"smoothing", "cubic", "quintic"}))
        ->capture_default_str();
    sub_->add_option("--side-frames", options_.side_frames, "Spline and DCT: valid frames needed on each side")
        ->capture_default_str();
    sub_->add_option("--donor", options_.donors, "Pattern fill: MARKER=DONOR (repeatable); others choose a donor");
    sub_->add_option("--models", options_.models, "Model file from csw fit, for --fill model");
    sub_->add_option("--filter", options_.filter, "Low-pass filter after filling: butterworth or kalman")
        ->check(CLI::IsMember({"butterworth", "kalman"}));
    sub_->add_option("--cutoff", options_.cutoff_hz, "Butterworth: -3 dB frequency of the zero-phase filter (Hz)")
        ->capture_default_str();
    sub_->add_option("--order", options_.order, "Butterworth: order of one pass (2, 4, 6, 8)")->capture_default_str();
    sub_->add_option("--kalman-model", options_.kalman_model, "Kalman: velocity or acceleration")
        ->check(CLI::IsMember({"velocity", "acceleration"}))
        ->capture_default_str();
    sub_->add_flag("--fix-spikes", options_.fix_spikes, "Remove the detected spike samples (then fill them)");
    sub_->add_flag("--fix-swaps", options_.fix_swaps, "Exchange back the markers of each detected label swap");
    sub_->add_flag("--dry-run", options_.dry_run, "Report only: write no take");
    sub_->add_option("--truth", options_.truth,
                     "Folder with <take>.clean.c3d (csw simulate --clean): score every filled sample against it");
    sub_->add_option("--figures", options_.figures, "Folder for each take's gap map and its longest filled gap (PNG)");
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Clean(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::CleanText(r);
    }
    return 0;
  }

 private:
  jobs::CleanOptions options_;
  bool json_ = false;
};

class SegmentCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("segment",
                              "Refine the manual sign/transition boundaries of sign-language takes: each boundary "
                              "moves to the nearest minimum of each hand's filtered wrist speed within a threshold, "
                              "giving one tier per hand (docs/signing.md)");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes, comma-separated names or glob patterns ('signs0*'); \\ escapes * ? [ ] @ , "
                     "(docs/cli.md); default every take but fill versions");
    sub_->add_option("--tier", options_.tier, "The manual sign/transition interval tier")->required();
    sub_->add_option("--hand", options_.hand, "Hands to refine: right, left or both")
        ->check(CLI::IsMember({"right", "left", "both"}))
        ->capture_default_str();
    sub_->add_option("--cutoff-hz", options_.cutoff_hz,
                     "-3 dB frequency of the zero-phase low-pass filter on the wrist positions (0 = none)")
        ->capture_default_str();
    sub_->add_option("--order", options_.order, "Butterworth order of one pass (2, 4, 6, 8)")->capture_default_str();
    sub_->add_option("--threshold-s", options_.threshold_s,
                     "A boundary moves only to a minimum at most this far (the seed: 0.15 s = 15 frames at 100 Hz)")
        ->capture_default_str();
    sub_->add_option("--rest-speed", options_.rest_speed_mm_s,
                     "mm/s; > 0: a hand slower than this for --min-rest-s is at rest, and its arrival and departure "
                     "are its minima (0 = the seed's plain minima)")
        ->capture_default_str();
    sub_->add_option("--min-rest-s", options_.min_rest_s, "Shortest rest for --rest-speed, in seconds")
        ->capture_default_str();
    sub_->add_option("--right-wrist", options_.right_wrist,
                     "Right wrist marker (default: a name with 'wrist' or ending in 'hand' and a right side)");
    sub_->add_option("--left-wrist", options_.left_wrist, "Left wrist marker (default: the naming rules)");
    sub_->add_option("--right-tier", options_.right_tier, "Output tier of the right hand (default <tier>_right)");
    sub_->add_option("--left-tier", options_.left_tier, "Output tier of the left hand (default <tier>_left)");
    sub_->add_flag("--dry-run", options_.dry_run, "Report only: write no tier");
    sub_->add_option("--figures", options_.figures,
                     "Folder for one figure per take: wrist speeds with the manual and refined tiers (PNG)");
    sub_->add_option("--figure-tiers", options_.figure_tiers,
                     "More tiers to draw in the figures (comma-separated), e.g. a simulation's right_hand,left_hand")
        ->delimiter(',');
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Segment(options_, progress);
    if (json_)
      PrintJson(r);
    else
      std::cout << jobs::SegmentText(r);
    return 0;
  }

 private:
  jobs::SegmentOptions options_;
  bool json_ = false;
};

class VideoCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("video",
                              "A point-light MP4 of one take's markers seen from the front, with a frame counter; "
                              "audio muxed by ffmpeg when installed (docs/video.md)");
    sub_->add_option("input", options_.input, "A C3D file, or a corpus (.h5) with --take")->required();
    sub_->add_option("--take", options_.take, "The corpus take");
    sub_->add_option("-o,--output", options_.output, "The MP4 to write")->required();
    sub_->add_option("--fps", options_.fps, "Video frames per second")->capture_default_str();
    sub_->add_option("--size", options_.size, "WIDTHxHEIGHT in pixels (even, 64-4096)")->capture_default_str();
    sub_->add_option("--audio", options_.audio,
                     "WAV to mux (needs ffmpeg; silent with a warning without it); the video lasts as long");
    sub_->add_option("--markerset", options_.markerset,
                     "Marker-set JSON (front view, colours, sticks); default the one the corpus remembers, else "
                     "none (lab axes)");
    sub_->add_option("--ffmpeg", options_.ffmpeg, "The ffmpeg program (a path or a name on PATH)")
        ->capture_default_str();
    sub_->add_option("--png", options_.png, "Also write one frame as a PNG");
    sub_->add_option("--png-time", options_.png_time_s, "Time of that frame in seconds")->capture_default_str();
    sub_->add_flag("--json", json_, "Print the result as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Video(options_, progress);
    if (json_)
      PrintJson(r);
    else
      std::cout << jobs::VideoText(r);
    return 0;
  }

 private:
  jobs::VideoOptions options_;
  bool json_ = false;
};

class CueCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("cue",
                              "Expected Cued Speech keys of a phone alignment (IPA, X-SAMPA, SPPAS or MFA symbols): "
                              "an interval tier 'expected_keys' written into each take of a corpus, or into a copy "
                              "of a TextGrid (docs/phonetics.md)");
    sub_->add_option("input", options_.input, "Corpus (.h5) or TextGrid")->required();
    sub_->add_option("-o,--output", options_.output, "TextGrid input: the TextGrid to write");
    sub_->add_option("--takes", options_.takes,
                     "Corpus: takes, comma-separated names or glob patterns (docs/cli.md); default every take but "
                     "fill versions");
    sub_->add_option("--phones", options_.phones, "The phone tier")->capture_default_str();
    sub_->add_option("--symbols", options_.symbols, "Phone symbols: auto, ipa, mfa (= ipa), xsampa or sppas")
        ->capture_default_str();
    sub_->add_option("--tier", options_.tier, "Name of the tier written")->capture_default_str();
    sub_->add_flag("--dry-run", options_.dry_run, "Report only: write nothing");
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Cue(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::CueText(r);
    }
    return 0;
  }

 private:
  jobs::CueOptions options_;
  bool json_ = false;
};

class KeysCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("keys",
                              "Gaussian key recogniser (docs/analysis.md): train on labelled target frames, "
                              "score takes (gestural score, decoded key tiers)");
    sub_->require_subcommand(1);
    train_ = sub_->add_subcommand("train",
                                  "Train the shape and placement Gaussians on labelled target frames and "
                                  "save them into a model file (group /keys)");
    train_->add_option("corpus", train_options_.corpus, "Corpus file")->required();
    train_
        ->add_option("--takes", train_options_.takes,
                     "Training takes, comma-separated names, name@first:end or glob patterns (docs/cli.md)")
        ->required();
    train_->add_option("--tier", train_options_.tier, "Point tier of shape targets (codes PS)")->capture_default_str();
    train_
        ->add_option("--placement-tier", train_options_.placement_tier,
                     "Point tier of placement targets, when the take has it")
        ->capture_default_str();
    train_->add_option("--markerset", train_options_.markerset,
                       "Marker-set JSON; default the one each take was imported with");
    train_->add_option("--layout", train_options_.layout,
                       "JSON file with a hand_layout section naming the finger, palm and head markers");
    train_
        ->add_option("--shrinkage", train_options_.model.shape.shrinkage_samples,
                     "Covariance shrinkage towards the pooled covariance, in samples")
        ->capture_default_str();
    train_
        ->add_option("--min-variance", train_options_.model.shape.min_variance,
                     "Variance added to every covariance diagonal (mm²)")
        ->capture_default_str();
    train_->add_option("--priors", priors_, "Class priors: uniform or counts")
        ->check(CLI::IsMember({"uniform", "counts"}))
        ->capture_default_str();
    train_->add_option("-o,--output", train_options_.output, "Model file (HDF5; other models in it are kept)")
        ->required();
    train_->add_flag("--json", json_, "Print the summary as JSON");
    score_ = sub_->add_subcommand("score",
                                  "Score takes with a key model: write the decoded keys and gesture extents "
                                  "as tiers; with label tiers, report accuracies");
    score_->add_option("corpus", score_options_.corpus, "Corpus file")->required();
    score_->add_option("--keys", score_options_.keys, "Model file with a key model (csw keys train)")->required();
    score_->add_option("--takes", score_options_.takes,
                       "Takes, comma-separated names or glob patterns; default every take but fill versions");
    score_->add_option("--tier", score_options_.tier, "Label tier to score against, when present")
        ->capture_default_str();
    score_
        ->add_option("--placement-tier", score_options_.placement_tier,
                     "Point tier of placement targets, when present (else --tier)")
        ->capture_default_str();
    score_->add_option("--markerset", score_options_.markerset,
                       "Marker-set JSON; default the one each take was imported with");
    score_
        ->add_option("--phones", score_options_.phones,
                     "Phone tier whose keys anchor the aligned target times to the speech when they match the "
                     "labels (\"\" = never)")
        ->capture_default_str();
    score_->add_option("--min-key", score_options_.decode.min_key_ms, "Free decoding: shortest key (ms)")
        ->capture_default_str();
    score_
        ->add_option("--aligned-floor", score_options_.decode.aligned_floor,
                     "Aligned decoding: posterior floor before the log, (0, 1) (docs/analysis.md)")
        ->capture_default_str();
    score_->add_flag("!--no-anchor-nearest", score_options_.anchor_nearest,
                     "Speech anchors: do not replace a target that lies nearer a neighbouring key's A1 + lag than "
                     "its own (docs/analysis.md)");
    score_
        ->add_option("--fit-sd-factor", score_options_.fit_sd_factor,
                     "Speech anchors: a kept fitted target is combined with its A1 + lag by inverse variance, the "
                     "fit's standard error multiplied by this; 0 = fits kept (docs/analysis.md)")
        ->capture_default_str();
    score_->add_flag("!--no-keep-in-class", score_options_.keep_in_class,
                     "Speech anchors: replace a fitted target beyond the gate even where the hand holds the key's "
                     "own class (docs/analysis.md)");
    score_->add_flag("--dry-run", score_options_.dry_run, "Report only: write no tier nor scores");
    score_->add_option("--figures", score_options_.figures,
                       "Folder for the shape and placement confusion matrices (PNG), when takes have labels");
    score_->add_flag("--json", json_, "Print the report as JSON");
    suggest_ = sub_->add_subcommand("suggest",
                                    "Propose a target frame for every expected key (the hand-speed minimum nearest "
                                    "its expected time): point tiers keys_suggested and placement_suggested");
    suggest_->add_option("corpus", suggest_options_.corpus, "Corpus file")->required();
    suggest_->add_option("--takes", suggest_options_.takes,
                         "Takes, comma-separated names or glob patterns; default every take but fill versions");
    suggest_->add_option("--phones", suggest_options_.phones, "The phone tier")->capture_default_str();
    suggest_->add_option("--symbols", suggest_options_.symbols, "Phone symbols: auto, ipa, mfa, xsampa or sppas")
        ->capture_default_str();
    suggest_->add_option("--markerset", suggest_options_.markerset,
                         "Marker-set JSON; default the one each take was imported with");
    suggest_->add_option("--layout", suggest_options_.layout,
                         "JSON file with a hand_layout section naming the finger, palm and head markers");
    suggest_->add_option("--phasing", suggest_options_.phasing,
                         "Phasing model JSON for the expected target times (default: Attina's means)");
    suggest_->add_option("--cutoff", suggest_options_.suggest.cutoff_hz, "Low-pass cut-off of the features (Hz)")
        ->capture_default_str();
    suggest_->add_option("--search", suggest_options_.suggest.search_s, "Half-width of the search window (s)")
        ->capture_default_str();
    suggest_->add_option("--tier", suggest_options_.tier, "Point tier of the suggested shape targets")
        ->capture_default_str();
    suggest_
        ->add_option("--placement-tier", suggest_options_.placement_tier,
                     "Point tier of the suggested placement targets")
        ->capture_default_str();
    suggest_->add_flag("--dry-run", suggest_options_.dry_run, "Report only: write no tier");
    suggest_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (train_->parsed()) {
      PriorKind kind = PriorKind::kUniform;
      keys::ParsePriorKind(priors_, &kind);
      train_options_.model.shape.priors = kind;
      train_options_.model.placement.priors = kind;
      train_options_.model.placement.shrinkage_samples = train_options_.model.shape.shrinkage_samples;
      train_options_.model.placement.min_variance = train_options_.model.shape.min_variance;
      if (std::string why = train_options_.Check(); !why.empty()) throw UsageError(why);
      const nlohmann::json r = jobs::KeysTrain(train_options_, progress);
      if (json_) {
        PrintJson(r);
      } else {
        std::cout << jobs::KeysTrainText(r);
      }
      return 0;
    }
    if (suggest_->parsed()) {
      if (std::string why = suggest_options_.Check(); !why.empty()) throw UsageError(why);
      const nlohmann::json r = jobs::KeysSuggest(suggest_options_, progress);
      if (json_) {
        PrintJson(r);
      } else {
        std::cout << jobs::KeysSuggestText(r);
      }
      return 0;
    }
    if (std::string why = score_options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::KeysScore(score_options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::KeysScoreText(r);
    }
    return 0;
  }

 private:
  using PriorKind = keys::PriorKind;
  CLI::App* train_ = nullptr;
  CLI::App* score_ = nullptr;
  CLI::App* suggest_ = nullptr;
  jobs::KeysTrainOptions train_options_;
  jobs::KeysScoreOptions score_options_;
  jobs::KeysSuggestOptions suggest_options_;
  std::string priors_ = "uniform";
  bool json_ = false;
};

class PhasingCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("phasing",
                              "Hand-speech phasing: onset and target of every key's shape and placement gestures "
                              "(kinematic and posterior), relative to A1, per key type (docs/analysis-phasing.md)");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("--keys", options_.keys, "Model file with a key model (csw keys train)")->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes, comma-separated names or glob patterns; default every take but fill versions");
    sub_->add_option("--phones", options_.phones, "The phone tier")->capture_default_str();
    sub_->add_option("--symbols", options_.symbols, "Phone symbols: auto, ipa, mfa, xsampa or sppas")
        ->capture_default_str();
    sub_->add_option("--markerset", options_.markerset, "Marker-set JSON; default the one each take was imported with");
    sub_->add_option("--csv", options_.csv, "Write one row per key (times on the take's clock and from A1)");
    sub_->add_option("--figures", options_.figures, "Folder for the histograms and gestural scores (PNG)");
    sub_->add_option("--truth", options_.truth,
                     "Folder with <take>.truth.json (csw simulate): true times beside the estimates");
    sub_->add_option("--reference", options_.reference,
                     "Phasing model JSON drawn as the histograms' reference (default: Attina's means)");
    sub_->add_option("--targets", options_.targets,
                     "Rough target times: labels (tiers keys / placement_targets), aligned (decoding) or auto")
        ->capture_default_str();
    sub_->add_option("--tier", options_.labels, "Point tier of labelled shape targets")->capture_default_str();
    sub_->add_option("--placement-tier", options_.label_placement,
                     "Point tier of labelled placement targets (absent: the shape targets seed the placement fits, "
                     "refitted once from their first targets)")
        ->capture_default_str();
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Phasing(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::PhasingText(r);
    }
    return 0;
  }

 private:
  jobs::PhasingOptions options_;
  bool json_ = false;
};

class DictCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("dict", "Unit dictionaries of the synthesizer (docs/dictionary-format.md)");
    sub_->require_subcommand(1);
    CLI::App* b = sub_->add_subcommand(
        "build",
        "The dikey dictionary: every movement between two successive keys (rest 00 included), with hand-shape "
        "parameters, forearm pose relative to the head and head pose per frame, and its coverage report");
    b->add_option("corpus", options_.corpus, "Corpus file")->required();
    b->add_option("--models", options_.models, "Model file with a face and a hand model (csw fit)")->required();
    b->add_option("--keys", options_.keys, "Key model file (csw keys train), recorded in the dictionary");
    b->add_option("-o,--output", options_.output, "Dictionary file (HDF5, replaced)")->required();
    b->add_option("--takes", options_.takes,
                  "Takes, comma-separated names or glob patterns; default every take but fill versions");
    b->add_option("--tier", options_.tier, "Key tier: keys_aligned (csw keys score) or keys (labels)")
        ->capture_default_str();
    b->add_option("--placement-tier", options_.placement_tier,
                  "Point tier of placement targets: each key's placement lag, written into csw say's "
                  "placement_targets (\"\" = none)")
        ->capture_default_str();
    b->add_option("--phones", options_.phones, "Phone tier for the per-dikey phasing and the diphones (\"\" = none)")
        ->capture_default_str();
    b->add_option("--max-unsolved", options_.dikeys.max_unsolved_fraction,
                  "Leave out a dikey with more than this fraction of unsolved frames")
        ->capture_default_str();
    b->add_option("--threads", options_.threads, "Takes inverted in parallel (0 = hardware threads)")
        ->capture_default_str();
    b->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::DictBuild(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::DictBuildText(r);
    }
    return 0;
  }

 private:
  jobs::DictBuildOptions options_;
  bool json_ = false;
};

class SayCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("say",
                              "Text-to-cued-speech synthesis (docs/synthesis.md): French text -> speech.wav, "
                              "cues.TextGrid, markers.c3d, pointlight.mp4 from a dictionary (csw dict build)");
    sub_->add_option("text", options_.texts, "French sentence(s) to synthesise");
    sub_->add_option("--text-file", options_.text_file, "A file of sentences, one per line ('#' = comment)");
    sub_->add_option("--dict", options_.dict, "Dictionary file (csw dict build)")->required();
    sub_->add_option("--models", options_.models, "The model file the dictionary was built with")->required();
    sub_->add_option("-o,--output", options_.output,
                     "Output folder (created; one sub-folder per sentence when several)")
        ->required();
    sub_->add_option("--rate", options_.rate_wpm,
                     "Speaking rate (espeak-ng words per minute); default: the corpus's mean phone duration");
    sub_->add_option("--phasing", options_.phasing,
                     "Key timing: dikey (the phasing each dikey stored) or global (the seed's rule)")
        ->capture_default_str();
    sub_->add_option("--frame-rate", options_.rate_hz, "Marker frame rate (Hz); 0 = the corpus's")
        ->capture_default_str();
    sub_->add_option("--fps", options_.fps, "Point-light video frame rate")->capture_default_str();
    sub_->add_option("--selection-weight", options_.selection_weight,
                     "Unit selection: cost per second of RMS duration mismatch (docs/synthesis.md)")
        ->capture_default_str();
    sub_->add_option("--concatenation-weight", options_.concatenation_weight,
                     "Unit selection: cost per standardised RMS parameter jump at a join")
        ->capture_default_str();
    sub_->add_option("--target-weight", options_.target_weight,
                     "Unit selection: cost per standardised distance of a unit's key postures from their classes' "
                     "means (0 = off)")
        ->capture_default_str();
    sub_->add_flag("--keep-key-postures,!--no-keep-key-postures", options_.keep_key_postures,
                   "A dikey trimmed to fit a short slot still starts at its key's posture (default: on; more keys "
                   "reached; docs/synthesis.md)");
    sub_->add_flag("--keep-movement-durations", options_.keep_movement_durations,
                   "Each dikey's movements keep their corpus duration and the holds before them fit the slot, "
                   "instead of warping whole units linearly (default: off; docs/synthesis.md)");
    sub_->add_flag("--movement-onsets", options_.movement_onsets,
                   "Each dikey's movements start at their syllable's A1 plus the unit's own onset phasing, "
                   "overlapping the previous key when that is earlier (default: off; --keep-movement-durations "
                   "replaces it; docs/synthesis.md)");
    sub_->add_option("--max-overlap", options_.max_onset_overlap,
                     "--movement-onsets: how far a movement may start before its slot, as a fraction of the "
                     "previous slot (0-1)")
        ->capture_default_str();
    sub_->add_option("--posture-radius", options_.posture_radius,
                     "Key posture pull: a hand farther than this (in its key code's standard deviations) from the "
                     "code's mean posture is moved toward the code's exemplar (0 = off; docs/synthesis.md)")
        ->capture_default_str();
    sub_->add_option("--face-units", options_.face_units,
                     "The face from diphones (Viterbi) or fragments (seed-003: greedy longest match, phone-aligned "
                     "warp, RBF resampling, blended overlaps)")
        ->capture_default_str();
    sub_->add_option("--resampling", options_.resampling, "Fragments: rbf (inverse multiquadric) or linear")
        ->capture_default_str();
    sub_->add_option("--rbf-shape", options_.rbf_shape,
                     "Fragments: inverse-multiquadric shape c in smallest sample spacings (wider = smoother on "
                     "clean data, more overshoot on noisy data)")
        ->capture_default_str();
    sub_->add_option("--blend", options_.blend, "Fragments: overlap at each join, fraction of the shared phone (0-1)")
        ->capture_default_str();
    sub_->add_flag("--no-video", no_video_, "Do not write pointlight.mp4");
    sub_->add_flag("--check", options_.check,
                   "Score the synthesised markers with the key recogniser, measure continuity and timing");
    sub_->add_option("--keys", options_.keys, "Key model file (csw keys train), for --check");
    sub_->add_option("--corpus-phasing", options_.corpus_phasing,
                     "JSON of csw phasing --json on the corpus, the timing --check compares with");
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    options_.video = !no_video_;
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Say(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::SayText(r);
    }
    return 0;
  }

 private:
  jobs::SayOptions options_;
  bool no_video_ = false;
  bool json_ = false;
};

class DemoCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("demo",
                              "The whole cued-speech pipeline on the demo corpus (import, fit, invert, keys, phasing, "
                              "dictionaries, synthesis) and one HTML page of it: DIR/report/index.html");
    sub_->add_option("-o,--output", options_.output, "Output folder (created)")->required();
    sub_->add_option("--source", options_.source,
                     "Demo corpus folder (sub-folders with a markerset.json); default the shipped datasets/demo");
    sub_->add_option("--cued", options_.cued, "The source's sub-folder of cued takes (with a key tier)")
        ->capture_default_str();
    sub_->add_option("--takes", options_.cued_takes, "Use the first N cued takes (0 = all)")->capture_default_str();
    sub_->add_option("--config", options_.config,
                     "Model configuration for csw fit; default datasets/configs/virtual-cuer.json");
    sub_->add_option("--sentences-file", options_.sentences_file,
                     "Sentences to synthesise, one per line; default datasets/unseen_sentences_fr.txt");
    sub_->add_option("--sentences", options_.sentences, "Synthesise the first N of them (0 = no synthesis)")
        ->capture_default_str();
    sub_->add_flag("--no-video", no_video_, "Do not write the point-light videos");
    sub_->add_option("--threads", options_.threads, "Takes inverted in parallel (0 = hardware threads)")
        ->capture_default_str();
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    options_.video = !no_video_;
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Demo(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::DemoText(r);
    }
    return 0;
  }

 private:
  jobs::DemoOptions options_;
  bool no_video_ = false;
  bool json_ = false;
};

class CoarticCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("coartic",
                              "Öhman's coarticulation model (docs/coarticulation.md): fit it on symmetric VCV takes, "
                              "generate parameter trajectories for a phone string");
    sub_->require_subcommand(1);
    fit_ = sub_->add_subcommand("fit",
                                "Fit on symmetric VCV takes inverted with a face model: per consonant w_c(x), c(x), "
                                "k_c(t) and its stylisation");
    CLI::App* f = fit_;
    f->add_option("corpus", options_.corpus, "Corpus file")->required();
    f->add_option("--models", options_.models, "Model file with a face model (csw fit face)")->required();
    f->add_option("--takes", options_.takes,
                  "Takes, comma-separated names or glob patterns (e.g. 'visemes_*': isolated vowels and VCV); "
                  "default every take but fill versions");
    f->add_option("--phones", options_.phones, "The phone tier (IPA)")->capture_default_str();
    f->add_option("--vowels", options_.fit.vowels, "The symmetric vowel contexts")
        ->delimiter(',')
        ->capture_default_str();
    f->add_option("--min-w", options_.fit.min_w, "Below this |w|, c(x) is not identifiable")->capture_default_str();
    f->add_option("--min-vowel-spread", options_.fit.min_vowel_spread,
                  "w(x) is fitted only where the vowel contexts spread over this fraction of x's range")
        ->capture_default_str();
    f->add_option("--min-effect", options_.fit.min_effect,
                  "Per-parameter k(t) only where |w (c - v)| is at least this fraction of the parameter's range")
        ->capture_default_str();
    f->add_option("-o,--output", options_.output, "Write the fit (JSON, format csw-ohman)");
    f->add_option("--figures", options_.figures, "Folder for the k(t) figures (PNG), one per consonant");
    f->add_flag("--json", json_, "Print the report as JSON");
    generate_ = sub_->add_subcommand("generate",
                                     "Parameter trajectories for a phone string from a fit (csw coartic fit -o): the "
                                     "vocalic carrier, then the consonants in increasing w order; CSV and figure");
    CLI::App* g = generate_;
    g->add_option("fit", gen_.fit, "Fit file (JSON, csw coartic fit -o)")->required();
    g->add_option("--phones", gen_.phones,
                  "Phones (IPA) separated by spaces, each optionally with :MS, its duration; _ is a pause, e.g. "
                  "\"_ a p:100 a _\"");
    g->add_option("--textgrid", gen_.textgrid, "Or: a TextGrid whose phone tier gives the phones and times");
    g->add_option("--tier", gen_.tier, "The TextGrid's phone tier")->capture_default_str();
    g->add_option("--vowel-ms", gen_.vowel_ms, "Duration of a vowel given without one")->capture_default_str();
    g->add_option("--consonant-ms", gen_.consonant_ms, "Duration of a consonant given without one")
        ->capture_default_str();
    g->add_option("--pause-ms", gen_.pause_ms, "Duration of a pause given without one")->capture_default_str();
    g->add_option("--rate", gen_.rate_hz, "Samples per second")->capture_default_str();
    g->add_flag("--skip-unknown", gen_.skip_unknown, "Leave out phones the fit does not know instead of failing");
    g->add_option("-o,--output", gen_.output, "CSV of the trajectories (time_s, one column per parameter)");
    g->add_option("--figures", gen_.figures, "Folder for generated.png");
    g->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (generate_->parsed()) {
      if (std::string why = gen_.Check(); !why.empty()) throw UsageError(why);
      const nlohmann::json r = jobs::CoarticGenerate(gen_, progress);
      if (json_) {
        PrintJson(r);
      } else {
        std::cout << jobs::CoarticGenerateText(r);
      }
      return 0;
    }
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Ohman(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::OhmanText(r);
    }
    return 0;
  }

 private:
  CLI::App* fit_ = nullptr;
  CLI::App* generate_ = nullptr;
  jobs::OhmanJobOptions options_;
  jobs::CoarticGenerateOptions gen_;
  bool json_ = false;
};

class TransitionsCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("transitions",
                              "Sign-language transitions: durations and posture distances per hand, statistics per "
                              "transition type, and the duration models SIMPLE, SIMPLE_BOUNDED, LINEAR and SURFACE "
                              "fitted and cross-validated (docs/transitions.md)");
    sub_->add_option("corpus", options_.corpus, "Corpus file (skeleton captures: BVH or csw simulate signs)")
        ->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes, comma-separated names or glob patterns; default every take but fill versions");
    sub_->add_option("--tiers", options_.tiers, "Sign/transition interval tiers, one per hand")
        ->delimiter(',')
        ->capture_default_str();
    sub_->add_option("--types", options_.types, "Sign-type interval tier (00, 10, 11, 20 or one_hand, ...); '' = none")
        ->capture_default_str();
    sub_->add_option("--wrists", options_.wrists,
                     "TIER=JOINT pairs naming each hand tier's wrist joint (default: found by name and side)")
        ->delimiter(',');
    sub_->add_option("--joints", options_.joints, "Joints averaged: arm (the hand's arm, shoulder to tips) or all")
        ->capture_default_str();
    sub_->add_option("--length-unit", options_.length_unit, "Unit of Euclidean distances: m, dm, cm or mm")
        ->capture_default_str();
    sub_->add_option("--models", options_.models, "Duration models: simple, simple_bounded, linear, surface")
        ->delimiter(',')
        ->capture_default_str();
    sub_->add_option("--folds", options_.folds, "Cross-validation folds")->capture_default_str();
    sub_->add_option("--min-s", options_.model.min_s, "SIMPLE_BOUNDED lower limit (s)")->capture_default_str();
    sub_->add_option("--max-s", options_.model.max_s, "SIMPLE_BOUNDED upper limit (s)")->capture_default_str();
    sub_->add_option("--max-transition-s", options_.transition.max_transition_s,
                     "A longer gap between two signs is a pause, not a transition (s)")
        ->capture_default_str();
    sub_->add_option("-o,--output", options_.output, "Save the fitted models (JSON)");
    sub_->add_option("--csv", options_.csv, "Write one row per transition");
    sub_->add_option("--figures", options_.figures, "Folder for the figure transitions.png");
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::Transitions(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::TransitionsText(r);
    }
    return 0;
  }

 private:
  jobs::TransitionsOptions options_;
  bool json_ = false;
};

class SignSequenceCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("sign-sequence",
                              "Synthesise a sign utterance from captured signs: motion retrieval of one occurrence per "
                              "gloss, transitions by interpolation or blending with a duration model; writes BVH and "
                              "TextGrid (docs/transitions.md)");
    sub_->add_option("corpus", options_.corpus, "Corpus file with skeleton takes")->required();
    sub_->add_option("--glosses", options_.glosses, "The signs of the utterance, in order (comma-separated)")
        ->delimiter(',')
        ->required();
    sub_->add_option("--takes", options_.takes,
                     "Takes to cut signs from, comma-separated names or glob patterns; default every take");
    sub_->add_option("--tier", options_.tier, "Interval tier whose labels are glosses")->capture_default_str();
    sub_->add_option("--durations", options_.durations,
                     "Duration models file of csw transitions -o (default: the seed's SURFACE plane)");
    sub_->add_option("--model", options_.model, "Model of that file (default: its best)");
    sub_->add_option("--method", options_.method, "Transitions: blend or interpolate")->capture_default_str();
    sub_->add_flag("--smooth", options_.smooth, "Blend with smooth (3u^2 - 2u^3) instead of linear weights");
    sub_->add_option("-o,--output", options_.output, "Output BVH file (a .TextGrid is written beside it)")->required();
    sub_->add_flag("--json", json_, "Print the report as JSON");
  }
  int Run(Progress& progress) override {
    if (std::string why = options_.Check(); !why.empty()) throw UsageError(why);
    const nlohmann::json r = jobs::SignSequence(options_, progress);
    if (json_) {
      PrintJson(r);
    } else {
      std::cout << jobs::SignSequenceText(r);
    }
    return 0;
  }

 private:
  jobs::SignSequenceOptions options_;
  bool json_ = false;
};

class PackCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("pack",
                              "Write a corpus (index + its .d folder) as one self-contained file to send; "
                              "csw reads it like any corpus");
    sub_->add_option("corpus", options_.corpus, "Corpus file")->required();
    sub_->add_option("-o,--output", options_.output, "Output file (must not exist)")->required();
    sub_->add_flag("--json", json_, "Machine-readable JSON output");
  }
  int Run(Progress& progress) override {
    nlohmann::json r = jobs::Pack(options_, progress);
    if (json_)
      PrintJson(r);
    else
      std::cout << jobs::PackText(r);
    return 0;
  }

 private:
  jobs::PackOptions options_;
  bool json_ = false;
};

class UpgradeCommand : public Command {
 public:
  void Register(CLI::App& app) override {
    sub_ = app.add_subcommand("upgrade",
                              "Rewrite a version-1 or packed corpus as format version 2 (index + .d folder), "
                              "crash-safely; writing to it with any command does the same");
    sub_->add_option("corpus", corpus_, "Corpus file")->required();
    sub_->add_flag("--json", json_, "Machine-readable JSON output");
  }
  int Run(Progress& progress) override {
    nlohmann::json r = jobs::Upgrade(corpus_, progress);
    if (json_)
      PrintJson(r);
    else
      std::cout << jobs::UpgradeText(r);
    return 0;
  }

 private:
  std::string corpus_;
  bool json_ = false;
};

}  // namespace

std::vector<std::unique_ptr<Command>> MakeCommands() {
  std::vector<std::unique_ptr<Command>> c;
  c.push_back(std::make_unique<InspectCommand>());
  c.push_back(std::make_unique<ImportCommand>());
  c.push_back(std::make_unique<InfoCommand>());
  c.push_back(std::make_unique<ExportCommand>());
  c.push_back(std::make_unique<SimulateCommand>());
  c.push_back(std::make_unique<FitCommand>());
  c.push_back(std::make_unique<InvertCommand>());
  c.push_back(std::make_unique<CleanCommand>());
  c.push_back(std::make_unique<SegmentCommand>());
  c.push_back(std::make_unique<VideoCommand>());
  c.push_back(std::make_unique<CueCommand>());
  c.push_back(std::make_unique<KeysCommand>());
  c.push_back(std::make_unique<PhasingCommand>());
  c.push_back(std::make_unique<CoarticCommand>());
  c.push_back(std::make_unique<DictCommand>());
  c.push_back(std::make_unique<SayCommand>());
  c.push_back(std::make_unique<DemoCommand>());
  c.push_back(std::make_unique<TransitionsCommand>());
  c.push_back(std::make_unique<SignSequenceCommand>());
  c.push_back(std::make_unique<PackCommand>());
  c.push_back(std::make_unique<UpgradeCommand>());
  return c;
}

}  // namespace csw::cli
