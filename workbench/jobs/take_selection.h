#pragma once
// Take selection: the one syntax of `--takes` (and `fit --train`, its alias)
// for every command (docs/cli.md, "Selecting takes"). Works on a plain list of
// take names and frame counts, so it needs no corpus and is tested on its own.
//
// A selection is a list of arguments, each a comma-separated list of items:
//
//   name                 the whole take
//   name@first:end       frames [first, end) (0-based; either bound may be
//   name@:50%            omitted; a bound ending in % is a percentage of the
//   name@50%:            take's length, rounded down)
//   pattern[@range]      every take whose whole name matches the glob pattern:
//                        * any run of characters, ? one character, [abc] [a-z]
//                        one of a set, [!a-z] (or [^a-z]) none of a set
//
// A backslash makes the next character literal: \* \? \[ \] \@ \, \\ ("subj\@home",
// "a\,b"). An item that is exactly the name of a take (as typed, before any
// unescaping) always selects that whole take, so "subj@home" works unescaped.
// Otherwise the last unescaped '@' starts the range.
//
// Generated fill versions (see IsGeneratedFillVersion) are left out of the
// default selection (no item) and of pattern matches, unless the pattern
// itself contains ".filled"; they are selected when named.
//
// Errors (InvalidInput, each naming the item): an empty item, a malformed
// range or pattern, a name that is no take, a pattern that matches no take, a
// range outside the take or empty.
#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace csw::jobs {

// A take of the corpus, as the selection sees it.
struct TakeInfo {
  std::string name;
  int64_t frames = 0;
};

// One selected take: frames [first, first + count) of take `take`.
struct TakeRange {
  // Canonical item for this take: EscapeTakeName(take), plus "@" and the
  // range as given when one was given. Parsing it again (ParseTakeItem)
  // selects the same frames; stored in model files as training takes.
  std::string spec;
  std::string take;   // the take's name
  int64_t first = 0;  // first frame
  int64_t count = 0;  // frames selected (> 0)
};

// The arguments of --takes split at unescaped commas (escapes kept, so each
// item can be parsed with ParseTakeItem). "a,b\,c" → {"a", "b\,c"}.
std::vector<std::string> SplitTakeList(const std::vector<std::string>& arguments);

// Backslash-escapes the characters with a meaning in an item: \ * ? [ ] @ ,
std::string EscapeTakeName(const std::string& name);

// One parsed item (no take list needed).
struct TakeItem {
  std::string text;        // as given
  std::string name;        // unescaped name (literal items) or the pattern's text (unescaped, for messages)
  bool pattern = false;    // contains an unescaped * ? or [
  bool has_range = false;  // an unescaped '@' with a range after it
  std::string range;       // the range text after '@' ("first:end")
  bool Matches(const std::string& take_name) const;  // literal: equal; pattern: glob match of the whole name
  // Frames [first, first + count) of a take of `frames` frames; InvalidInput
  // naming the item when the range is empty or outside the take.
  void Resolve(int64_t frames, int64_t* first, int64_t* count) const;

  // Internal: the compiled pattern.
  struct Token {
    enum Kind { kLiteral, kAnyOne, kAnyRun, kSet } kind = kLiteral;
    char c = 0;
    bool negate = false;
    std::vector<std::pair<char, char>> ranges;  // kSet
  };
  std::vector<Token> tokens;
  int64_t first_value = 0, end_value = -1;  // end -1 = to the end
  bool first_percent = false, end_percent = false;
};

// Parses one item; InvalidInput naming it when malformed.
TakeItem ParseTakeItem(const std::string& item);

// True when `name` is a fill version made by `csw invert --fill`:
// "<original>.filled" or "<original>.filled-<k>" (k an integer ≥ 2 written
// without leading zeros) where a take named <original> is in `names`. Any
// other name containing ".filled" is an ordinary take.
bool IsGeneratedFillVersion(const std::string& name, const std::set<std::string>& names);

// The name `csw invert --fill` gives the next fill version of `take`:
// "<take>.filled", else "<take>.filled-2", "-3" … the first not in `existing`.
std::string FilledTakeName(const std::set<std::string>& existing, const std::string& take);

// Resolves a selection against the takes (in corpus order). No arguments (or
// only empty ones) = every take except generated fill versions. Returns the
// selected ranges in the order of the items (a pattern's matches in corpus
// order), each (take, frames) once. `where` prefixes error messages (e.g. the
// corpus path). InvalidInput when the selection is empty.
std::vector<TakeRange> SelectTakes(const std::vector<TakeInfo>& takes, const std::vector<std::string>& arguments,
                                   const std::string& where);

// True when the training item `spec` (as stored in a model file) selects
// frames of `range` (same take, overlapping frames). Specs stored before
// escapes existed ("subj@home" unescaped) still match their take.
bool TrainingSpecOverlaps(const std::string& spec, const TakeRange& range, int64_t take_frames);

}  // namespace csw::jobs
