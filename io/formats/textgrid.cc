#include "io/formats/textgrid.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <string_view>

#include "core/error.h"
#include "io/formats/text_util.h"

namespace csw {

namespace {

using formats_internal::FormatDouble;

struct Token {
  enum class Kind { kNumber, kString, kFlag, kEnd };
  Kind kind = Kind::kEnd;
  std::string text;
  int64_t line = 1;
};

// Splits Praat text into numbers, strings and <flags>, skipping every other word
// (the labels of the long format) and "!" comments.
class Lexer {
 public:
  Lexer(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  Token Next() {
    while (true) {
      SkipSeparators();
      Token tok;
      tok.line = line_;
      if (pos_ >= text_.size()) return tok;
      const char c = text_[pos_];
      if (c == '!') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        continue;
      }
      if (c == '"') {
        ReadString(&tok);
        return tok;
      }
      if (c == '<') {
        size_t end = pos_ + 1;
        while (end < text_.size() && text_[end] != '>' && !IsSeparator(text_[end])) ++end;
        if (end < text_.size() && text_[end] == '>') {
          tok.kind = Token::Kind::kFlag;
          tok.text = std::string(text_.substr(pos_, end + 1 - pos_));
          pos_ = end + 1;
          return tok;
        }
        SkipWord();
        continue;
      }
      if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || IsNonFiniteWord()) {
        size_t end = pos_;
        while (end < text_.size() && !IsSeparator(text_[end]) && text_[end] != '"') ++end;
        tok.kind = Token::Kind::kNumber;
        tok.text = std::string(text_.substr(pos_, end - pos_));
        pos_ = end;
        return tok;
      }
      SkipWord();
    }
  }

  int64_t remaining() const { return static_cast<int64_t>(text_.size() - pos_); }
  int64_t line() const { return line_; }

 private:
  static bool IsSeparator(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '=' || (static_cast<unsigned char>(c) < 0x20);
  }
  // "nan", "inf", "infinity" (any case) are read as (bad) numbers, not skipped
  // as labels, so that they are reported where they stand.
  bool IsNonFiniteWord() const {
    size_t end = pos_;
    while (end < text_.size() && !IsSeparator(text_[end]) && text_[end] != '"') ++end;
    std::string word(text_.substr(pos_, end - pos_));
    for (char& ch : word) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return word == "nan" || word == "inf" || word == "infinity";
  }
  void SkipSeparators() {
    while (pos_ < text_.size() && IsSeparator(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  void SkipWord() {
    while (pos_ < text_.size() && !IsSeparator(text_[pos_]) && text_[pos_] != '"') ++pos_;
  }
  void ReadString(Token* tok) {
    tok->kind = Token::Kind::kString;
    const int64_t start_line = line_;
    ++pos_;  // opening quote
    while (true) {
      if (pos_ >= text_.size()) {
        throw ParseError({path_, std::nullopt, start_line}, "unterminated string (no closing double quote)");
      }
      const char ch = text_[pos_];
      if (ch == '"') {
        if (pos_ + 1 < text_.size() && text_[pos_ + 1] == '"') {
          tok->text.push_back('"');
          pos_ += 2;
          continue;
        }
        ++pos_;
        return;
      }
      if (ch == '\r') {  // CRLF or a lone CR inside a string: one line break
        tok->text.push_back('\n');
        if (pos_ + 1 < text_.size() && text_[pos_ + 1] == '\n') {
          pos_ += 2;
          ++line_;  // lines are counted at '\n' only
        } else {
          ++pos_;
        }
        continue;
      }
      if (ch == '\n') ++line_;
      tok->text.push_back(ch);
      ++pos_;
    }
  }

  std::string_view text_;
  const std::string& path_;
  size_t pos_ = 0;
  int64_t line_ = 1;
};

class TextGridParser {
 public:
  TextGridParser(std::string_view text, const std::string& path) : lexer_(text, path), path_(path) {}

  std::vector<LabelTier> Parse(double* xmin_out, double* xmax_out) {
    Token tok = lexer_.Next();
    if (tok.kind != Token::Kind::kString || (tok.text != "ooTextFile" && tok.text != "ooTextFile short")) {
      throw Error(1, "not a Praat text file (expected File type = \"ooTextFile\")");
    }
    std::string object_class = ExpectString("the object class");
    if (object_class.rfind("TextGrid", 0) != 0) {
      throw Error(last_line_, "object class is \"" + object_class.substr(0, 40) + "\", not \"TextGrid\"");
    }
    const double xmin = ExpectNumber("the TextGrid xmin");
    const double xmax = ExpectNumber("the TextGrid xmax");
    if (xmin > xmax) {
      throw Error(last_line_, "TextGrid xmin " + FormatDouble(xmin) + " > xmax " + FormatDouble(xmax));
    }
    if (xmin_out) *xmin_out = xmin;
    if (xmax_out) *xmax_out = xmax;

    std::vector<LabelTier> tiers;
    tok = lexer_.Next();
    last_line_ = tok.line;
    if (tok.kind == Token::Kind::kFlag && tok.text == "<absent>") return tiers;
    if (tok.kind != Token::Kind::kFlag || tok.text != "<exists>") {
      throw Error(tok.line, "expected <exists> or <absent> for the tiers, found " + Describe(tok));
    }
    const int64_t tier_count = ExpectCount("the tier count", 16);
    for (int64_t t = 0; t < tier_count; ++t) {
      LabelTier tier;
      const std::string tier_class = ExpectString("the tier class");
      const int64_t class_line = last_line_;
      if (tier_class == "IntervalTier") {
        tier.kind = LabelTier::Kind::kInterval;
      } else if (tier_class == "TextTier") {
        tier.kind = LabelTier::Kind::kPoint;
      } else {
        throw Error(class_line,
                    "unknown tier class \"" + tier_class.substr(0, 40) + "\" (expected IntervalTier or TextTier)");
      }
      tier.name = ExpectString("the tier name");
      tier.start_s = ExpectNumber("the tier xmin");
      tier.end_s = ExpectNumber("the tier xmax");
      if (tier.start_s > tier.end_s) {
        throw Error(last_line_, "tier \"" + tier.name.substr(0, 40) + "\": xmin " + FormatDouble(tier.start_s) +
                                    " > xmax " + FormatDouble(tier.end_s));
      }
      const bool intervals = tier.kind == LabelTier::Kind::kInterval;
      const int64_t count = ExpectCount(intervals ? "the interval count" : "the point count", intervals ? 6 : 4);
      tier.labels.reserve(static_cast<size_t>(count));
      for (int64_t i = 0; i < count; ++i) {
        Label label;
        if (intervals) {
          label.start_s = ExpectNumber("an interval xmin");
          label.end_s = ExpectNumber("an interval xmax");
          if (label.start_s > label.end_s) {
            throw Error(last_line_, "tier \"" + tier.name.substr(0, 40) + "\", interval " + std::to_string(i + 1) +
                                        ": xmin " + FormatDouble(label.start_s) + " > xmax " +
                                        FormatDouble(label.end_s));
          }
          label.text = ExpectString("an interval text");
        } else {
          label.start_s = label.end_s = ExpectNumber("a point time");
          label.text = ExpectString("a point mark");
        }
        tier.labels.push_back(std::move(label));
      }
      tiers.push_back(std::move(tier));
    }
    return tiers;
  }

 private:
  ParseError Error(int64_t line, const std::string& what) const {
    return ParseError({path_, std::nullopt, line}, what);
  }
  static std::string Describe(const Token& tok) {
    switch (tok.kind) {
      case Token::Kind::kEnd:
        return "the end of the file";
      case Token::Kind::kNumber:
        return "the number " + tok.text.substr(0, 40);
      case Token::Kind::kString:
        return "the string \"" + tok.text.substr(0, 40) + "\"";
      case Token::Kind::kFlag:
        return "the flag " + tok.text.substr(0, 40);
    }
    return "?";
  }
  Token Expect(Token::Kind kind, const std::string& what) {
    Token tok = lexer_.Next();
    last_line_ = tok.line;
    if (tok.kind == Token::Kind::kEnd) {
      throw Error(tok.line, "unexpected end of file: expected " + what);
    }
    if (tok.kind != kind) {
      throw Error(tok.line, "expected " + what + ", found " + Describe(tok));
    }
    return tok;
  }
  std::string ExpectString(const std::string& what) {
    return std::move(Expect(Token::Kind::kString, what + " (a string)").text);
  }
  double ExpectNumber(const std::string& what) {
    Token tok = Expect(Token::Kind::kNumber, what + " (a number)");
    std::optional<double> v = formats_internal::ParseFiniteDouble(tok.text);
    if (!v) {
      throw Error(tok.line, what + ": '" + tok.text.substr(0, 40) + "' is not a finite number");
    }
    return *v == 0.0 ? 0.0 : *v;  // -0 -> 0
  }
  int64_t ExpectCount(const std::string& what, int64_t min_bytes_each) {
    const double v = ExpectNumber(what);
    if (v < 0 || v != std::floor(v)) {
      throw Error(last_line_, what + " " + FormatDouble(v) + " is not a non-negative integer");
    }
    if (v * static_cast<double>(min_bytes_each) > static_cast<double>(lexer_.remaining())) {
      throw Error(last_line_, what + " " + FormatDouble(v) + " is more than the remaining " +
                                  std::to_string(lexer_.remaining()) + " bytes can hold");
    }
    return static_cast<int64_t>(v);
  }

  Lexer lexer_;
  const std::string& path_;
  int64_t last_line_ = 1;
};

void AppendQuoted(const std::string& s, std::string* out) {
  out->push_back('"');
  for (char c : s) {
    if (c == '"') out->push_back('"');
    out->push_back(c);
  }
  out->push_back('"');
}

void CheckFinite(double v, const std::string& what) {
  if (!std::isfinite(v)) throw InvalidInput("WriteTextGrid: " + what + " is not finite");
}

}  // namespace

std::vector<LabelTier> ReadTextGrid(const std::string& path, double* xmin, double* xmax) {
  const std::string bytes = formats_internal::ReadFileBytes(path);
  if (bytes.empty()) throw ParseError({path, 0, std::nullopt}, "file is empty; not a TextGrid");
  if (bytes.rfind("ooBinaryFile", 0) == 0) {
    throw ParseError({path, 0, std::nullopt},
                     "binary TextGrid files are not supported; save "
                     "it from Praat as a text file");
  }
  const std::string text = formats_internal::DecodeText(bytes, path);
  TextGridParser parser(text, path);
  return parser.Parse(xmin, xmax);
}

void WriteTextGrid(const std::string& path, const std::vector<LabelTier>& tiers, double xmin, double xmax,
                   bool short_format) {
  CheckFinite(xmin, "xmin");
  CheckFinite(xmax, "xmax");
  if (xmin > xmax) throw InvalidInput("WriteTextGrid: xmin > xmax");
  std::string out;
  auto num = [&](const char* long_label, double v, const char* indent) {
    if (short_format) {
      out += FormatDouble(v) + "\n";
    } else {
      out += std::string(indent) + long_label + " = " + FormatDouble(v) + " \n";
    }
  };
  auto str = [&](const char* long_label, const std::string& s, const char* indent) {
    if (!short_format) out += std::string(indent) + long_label + " = ";
    AppendQuoted(s, &out);
    out += short_format ? "\n" : " \n";
  };
  out += "File type = \"ooTextFile\"\nObject class = \"TextGrid\"\n\n";
  num("xmin", xmin, "");
  num("xmax", xmax, "");
  if (tiers.empty()) {
    out += short_format ? "<absent>\n" : "tiers? <absent> \n";
  } else {
    out += short_format ? "<exists>\n" : "tiers? <exists> \n";
    if (short_format) {
      out += std::to_string(tiers.size()) + "\n";
    } else {
      out += "size = " + std::to_string(tiers.size()) + " \nitem []: \n";
    }
  }
  for (size_t t = 0; t < tiers.size(); ++t) {
    const LabelTier& tier = tiers[t];
    double tier_start = tier.start_s, tier_end = tier.end_s;
    if (tier_start == 0 && tier_end == 0 && !tier.labels.empty()) {
      tier_start = xmin;
      tier_end = xmax;
    }
    CheckFinite(tier_start, "tier \"" + tier.name + "\" start");
    CheckFinite(tier_end, "tier \"" + tier.name + "\" end");
    if (tier_start > tier_end) throw InvalidInput("WriteTextGrid: tier \"" + tier.name + "\" start > end");
    const bool intervals = tier.kind == LabelTier::Kind::kInterval;
    for (const Label& l : tier.labels) {
      CheckFinite(l.start_s, "a label time in tier \"" + tier.name + "\"");
      CheckFinite(l.end_s, "a label time in tier \"" + tier.name + "\"");
      if (intervals && l.start_s > l.end_s) {
        throw InvalidInput("WriteTextGrid: tier \"" + tier.name + "\" has a label with start > end");
      }
    }
    const std::vector<Label>& labels = tier.labels;
    if (!short_format) out += "    item [" + std::to_string(t + 1) + "]:\n";
    str("class", intervals ? "IntervalTier" : "TextTier", "        ");
    str("name", tier.name, "        ");
    num("xmin", tier_start, "        ");
    num("xmax", tier_end, "        ");
    if (short_format) {
      out += std::to_string(labels.size()) + "\n";
    } else {
      out += std::string("        ") + (intervals ? "intervals" : "points") +
             ": size = " + std::to_string(labels.size()) + " \n";
    }
    for (size_t i = 0; i < labels.size(); ++i) {
      if (!short_format) {
        out += std::string("        ") + (intervals ? "intervals" : "points") + " [" + std::to_string(i + 1) + "]:\n";
      }
      if (intervals) {
        num("xmin", labels[i].start_s, "            ");
        num("xmax", labels[i].end_s, "            ");
        str("text", labels[i].text, "            ");
      } else {
        num("number", labels[i].start_s, "            ");
        str("mark", labels[i].text, "            ");
      }
    }
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw IoError(path, "cannot open for writing");
  file.write(out.data(), static_cast<std::streamsize>(out.size()));
  file.close();
  if (!file) throw IoError(path, "write failed");
}

LabelTier FillIntervalGaps(const LabelTier& tier) {
  if (tier.kind != LabelTier::Kind::kInterval) return tier;
  LabelTier out = tier;
  out.labels.clear();
  out.labels.reserve(tier.labels.size() * 2 + 1);
  double cursor = tier.start_s;
  for (const Label& l : tier.labels) {
    if (l.start_s > cursor) out.labels.push_back({cursor, l.start_s, ""});
    out.labels.push_back(l);
    cursor = std::max(cursor, l.end_s);
  }
  if (cursor < tier.end_s) out.labels.push_back({cursor, tier.end_s, ""});
  return out;
}

}  // namespace csw
