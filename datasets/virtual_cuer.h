#pragma once
// The virtual cuer: realistic French Cued Speech motion captures with ground
// truth (docs/virtual-cuer.md). A take is built from
//   text -> Phonetise (espeak-ng phones, times, audio) -> CueKeys -> gesture
//   times (phasing model) -> hand joint angles and forearm pose (minimum-jerk
//   gestures), articulatory face parameters (Öhman coarticulation), head motion
//   -> 113 clean marker trajectories at rate_hz -> capture artefacts (noise,
//   camera occlusions, dropped samples, optional label swaps).
// Same options and seed -> identical takes and byte-identical files.
#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/markerset.h"
#include "core/progress.h"
#include "core/take.h"
#include "datasets/face_model.h"
#include "datasets/hand_model.h"
#include "datasets/placements.h"
#include "synth/cueing.h"
#include "synth/phasing.h"
#include "synth/phonetics.h"

namespace csw {

enum class CorpusKind { kShapes, kVisemes, kSentences };
const char* CorpusKindName(CorpusKind kind);  // "shapes", "visemes", "sentences"
bool ParseCorpusKind(const std::string& name, CorpusKind* kind);

struct SimulateOptions {
  CorpusKind kind = CorpusKind::kSentences;
  // Marker layout (SimulatorLayouts(), datasets/face_model.h): "default" or
  // "lab2" (another lab's markers: fewer face markers, 3 throat markers that
  // follow the head's translation fully and its rotation partly, 2-marker
  // phalanges, other names, a smaller hand).
  std::string layout = "default";
  // The hand's size relative to the layout's (0.5-2): every finger segment and
  // marker offset scaled, as for another cuer's hand.
  double hand_scale = 1.0;
  // Sentences to cue (kSentences); empty = the shipped list (datasets/sentences_fr.txt).
  std::vector<std::string> sentences;
  int count = 0;  // kSentences: first `count` sentences (0 = all)
  uint64_t seed = 1;
  double rate_hz = 120.0;  // capture frame rate
  // Capture artefacts.
  double noise_mm = 0.2;   // σ of the Gaussian marker noise per coordinate
  bool occlusions = true;  // line of sight of the virtual cameras
  int cameras = 8;
  int min_cameras = 2;           // a marker is reconstructed when seen by this many cameras
  double dropouts_per_s = 0.03;  // per marker: rate of short dropped-sample runs (1-6 frames)
  bool label_swaps = false;      // one temporary swap of two neighbouring hand markers per take
  // Timing. overlap_gestures: movement times drawn independently from the
  // phasing model's laws and overlapping gestures blended (superposition), so
  // the drawn times have the model's means; false: synth SampleTiming (each
  // movement starts after the previous target, no blending).
  PhasingModel phasing;
  bool overlap_gestures = true;
  // Peak speeds a movement may reach (0 = no limit). A drawn movement that would
  // be faster starts earlier (its target time is kept: the phasing laws are about
  // targets), so that its minimum-jerk peak (1.875 × distance / duration) stays
  // under the limit: the reference fingertip in the head frame, the forearm's
  // orientation angles, and each finger joint. Without them two independent
  // start/target draws can leave 60 ms for a 150 mm move (peaks of 5-10 m/s,
  // 30 mm second differences at 120 Hz); measured cueing moves peak near 1-2 m/s.
  double max_tip_speed_mm_s = 1500.0;
  double max_turn_speed_deg_s = 400.0;
  double max_joint_speed_deg_s = 1000.0;
  // Per-key variability of the targets (truncated at 2.5 sd): joint angles,
  // fingertip point and forearm orientation.
  double posture_sd_deg = 3.0;
  double placement_sd_mm = 3.0;
  double orientation_sd_deg = 2.0;
  int speech_rate_wpm = 80;   // espeak-ng speaking rate (cuers slow down: 300-400 ms keys)
  int viseme_rate_wpm = 130;  // speaking rate of uncued speech (the viseme corpus)
  bool audio = true;          // synthesise audio (false: espeak-ng phone times only)
  double lead_in_s = 0.6;     // capture before the audio and after the last movement
  // Outputs of SimulateCorpus.
  bool write_truth = true;   // <name>.truth.json
  bool write_clean = false;  // <name>.clean.c3d (markers without artefacts)
  // C3D storage: float (exact) or int16 at c3d_scale_mm steps (half the size; the
  // demo corpus uses it — quantisation σ = scale/√12, far below the marker noise).
  bool int16_c3d = false;
  double c3d_scale_mm = 0.05;
  // Configuration overrides ("" = shipped files, compiled in).
  std::string hand_config_path;
  std::string placement_config_path;

  std::string Check() const;  // "" when valid, else the reason
};

// How the take's time line is laid out: the capture starts at t = 0 (frame 0);
// the audio (padded with lead_in_s of silence) and every time below share it.
struct GestureTruth {
  Key key;                                                    // times shifted to the capture clock
  KeyTiming timing;                                           // movement start/target times on the capture clock
  Eigen::VectorXd posture;                                    // the key's actual joint-angle target (rad)
  Eigen::Vector3d placement_point = Eigen::Vector3d::Zero();  // actual fingertip target, head frame
};

// Frame state codes of the occlusion mask.
enum MarkerState : uint8_t { kVisible = 0, kOccluded = 1, kDropped = 2, kNotCaptured = 3 };

struct LabelSwap {
  int marker_a = 0, marker_b = 0;
  int64_t first_frame = 0, end_frame = 0;  // [first, end)
};

struct SimulationResult {
  Take take;                   // markers with artefacts, tiers, audio
  MarkerArray clean;           // same layout, no artefacts
  std::vector<uint8_t> state;  // frames × markers MarkerState
  Utterance utterance;         // phones and words on the capture clock
  std::vector<GestureTruth> keys;
  PhasingModel phasing;  // the model the gesture times were drawn from
  std::vector<std::string> joint_names;
  Eigen::MatrixXd joint_angles;  // frames × joints (radians)
  Eigen::MatrixXd articulation;  // frames × 6 (ArticulatoryParameter order)
  Eigen::MatrixXd head_motion;   // frames × 6: rotation vector (rad), translation (mm), about the reference head frame
  Eigen::MatrixXd forearm_pose;  // frames × 6: rotation vector (rad), translation (mm) of the forearm frame in the lab
  Eigen::Isometry3d head_reference = Eigen::Isometry3d::Identity();  // reference head frame in the lab
  std::vector<int> hand_columns;  // take columns of the hand markers (empty when no hand)
  std::vector<int> face_columns;  // take columns of the face markers (first columns)
  std::vector<int> face_markers;  // VirtualFace index of each face column
  std::vector<LabelSwap> swaps;
  std::vector<std::string> warnings;
  int64_t frames() const { return take.frames(); }
  double Time(int64_t frame) const { return static_cast<double>(frame) / take.rate_hz; }
};

// The virtual cuer's body: hand, face, placements and cameras.
class VirtualCuer {
 public:
  explicit VirtualCuer(const SimulateOptions& options);  // throws InvalidInput for bad options/config

  const VirtualHand& hand() const { return hand_; }
  const VirtualFace& face() const { return face_; }
  const PlacementConfig& placements() const { return placements_; }
  const SimulateOptions& options() const { return options_; }

  // The marker set describing every simulated marker (head cluster, face,
  // throat with head weights, forearm cluster, hand segments, sticks), or the
  // markers of one corpus: shapes = head cluster and hand, visemes = face only.
  MarkerSet MakeMarkerSet() const { return MakeMarkerSet(CorpusKind::kSentences); }
  MarkerSet MakeMarkerSet(CorpusKind kind) const;
  // All marker names (113 in the default layout), face first then hand.
  std::vector<std::string> AllMarkerNames() const;

  // A sentence from text (espeak-ng), cued or (visemes) without the hand.
  // Throws csw::Error when espeak-ng fails.
  SimulationResult SimulateSentence(const std::string& name, const std::string& text, bool cued = true) const;
  // A cued utterance from given phones (no espeak-ng needed; audio kept if present).
  SimulationResult SimulateUtterance(const std::string& name, const Utterance& utterance, bool cued = true) const;
  // Hand shapes in free space: rest, then the shapes in order, then rest. As in
  // the seed's separate camera setting, only the hand and the rigid head
  // markers are captured.
  SimulationResult SimulateShapes(const std::string& name, const std::vector<int>& shapes) const;

  // Gesture times of keys (capture clock), drawn as the options say.
  std::vector<KeyTiming> DrawTiming(const std::vector<Key>& keys, std::mt19937_64& rng) const;

  // Forearm frame in the head frame when a key is held: placement definition
  // 0-6 (6 = free space), shape 0-8.
  Eigen::Isometry3d ForearmInHead(int placement, int shape) const;
  // All markers (face then hand) in the lab for a held key, no head motion.
  Eigen::Matrix3Xd KeyFrame(int placement, int shape,
                            const ArticulatoryVector& face = ArticulatoryVector::Zero()) const;
  // The reference head frame in the lab (head centre 1.25 m above the lab origin).
  static Eigen::Isometry3d HeadReference();

  // Lab positions of the hand markers for joint angles and a forearm pose in the
  // lab (used by the renderer and the tests).
  Eigen::Matrix3Xd HandMarkersInLab(const Eigen::VectorXd& angles, const Eigen::Isometry3d& forearm_in_lab) const;

 private:
  struct Script;
  SimulationResult Run(const std::string& name, const Script& script) const;

  SimulateOptions options_;
  VirtualHand hand_;
  VirtualFace face_;
  VirtualFace anchor_face_;  // the default layout's face: placements anchor on its markers
  PlacementConfig placements_;
};

// An ordering of the 8 hand shapes in which every ordered pair of different
// shapes follows each other exactly once (an Eulerian circuit; 57 shapes).
std::vector<int> AllShapeTransitions();

// The shipped sentence list (datasets/sentences_fr.txt), one sentence a line.
std::vector<std::string> ShippedSentences();
const std::string& DefaultSentencesText();

// The viseme corpus texts (isolated vowels; VCV with V in {a, i, u}).
struct VisemeItem {
  std::string name;
  std::string text;
};
std::vector<VisemeItem> VisemeItems();

// One simulated take as files: <dir>/<name>.c3d, .wav (when audio), .TextGrid,
// .truth.json (write_truth), .clean.c3d (write_clean).
void WriteTakeFiles(const SimulationResult& result, const SimulateOptions& options, const std::string& dir);

// The TextGrid tiers of a take: words, phones, keys (points at the shape target
// times, "PS"), placement_targets (points), shape_gestures and
// placement_gestures (intervals start→target, clipped so they do not overlap).
std::vector<LabelTier> SimulationTiers(const SimulationResult& result);
// Ground truth as JSON text (deterministic formatting).
std::string TruthToJson(const SimulationResult& result);

// Writes the corpus of options.kind into out_dir (created if needed) with one
// markerset.json. Returns the take names. Reports progress; throws Cancelled.
std::vector<std::string> SimulateCorpus(const SimulateOptions& options, const std::string& out_dir, Progress& progress);

// The demo corpus: shapes, visemes and the first `sentences` shipped sentences,
// in out_dir/{shapes,visemes,sentences}, without clean copies (small: ≤ 20 MB).
void GenerateDemoCorpus(const std::string& out_dir, uint64_t seed, int sentences,
                        Progress& progress);  // 7 sentences: 20.6 MB
// The same with the capture options of `base` (rate, noise, occlusions,
// dropouts, label swaps, clean copies, sentences to cue); its kind, count,
// write_truth and int16_c3d are set per sub-corpus as above.
void GenerateDemoCorpus(const std::string& out_dir, const SimulateOptions& base, int sentences, Progress& progress);

}  // namespace csw
