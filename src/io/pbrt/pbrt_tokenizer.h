// The lexical level of pbrt scene files (v3 and v4 share it): words
// (directives, bare numbers, v4's bare true/false), quoted strings, '[' and
// ']', '#' comments. Every token keeps its line and column, so every error
// about the file, lexical or not, can say where it is.
#pragma once

#include <cstdint>
#include <string>

#include "core/error.h"
#include "io/byte_stream.h"

namespace ferry {

struct PbrtToken {
  enum class Kind : uint8_t { End, Word, String, OpenBracket, CloseBracket };
  Kind kind = Kind::End;
  // Word: as written. String: the contents, escapes resolved, without quotes.
  std::string text;
  int line = 0;    // 1-based
  int column = 0;  // 1-based, in bytes

  bool isNumber() const;  // a word that starts like a number (digit, sign, '.')
};

// Where a parameter list's tokens come from: one file (PbrtTokenizer), or a
// chain of included files (pbrt-v3 reads an included file and the file that
// included it as one stream, so a list may go on after the included file ends).
class PbrtTokenSource {
 public:
  virtual ~PbrtTokenSource() = default;
  virtual const PbrtToken& next() = 0;
  virtual const PbrtToken& peek() = 0;
  // Where `token`, the last one read or peeked, is.
  virtual SourceLocation where(const PbrtToken& token) const = 0;
};

// Reads tokens from a stream through its buffer; the file is never held whole.
// Lexical errors (an unterminated string or one broken by a newline, an
// unknown escape, a control byte, a token longer than 1 MiB) throw InputError
// at file:line:column.
class PbrtTokenizer final : public PbrtTokenSource {
 public:
  explicit PbrtTokenizer(ByteStream stream);

  // The next token; Kind::End at the end of the input (and ever after).
  const PbrtToken& next() override;
  // The token next() will return, without consuming it.
  const PbrtToken& peek() override;

  const std::string& fileName() const { return stream_.name(); }
  SourceLocation where(const PbrtToken& token) const override {
    return {stream_.name(), token.line, token.column};
  }
  uint64_t offset() const { return stream_.offset(); }
  uint64_t size() const { return stream_.size(); }

 private:
  void scan(PbrtToken& token);
  [[noreturn]] void fail(int line, int column, const std::string& message) const;

  ByteStream stream_;
  PbrtToken current_, lookahead_;
  bool hasLookahead_ = false;
  int line_ = 1, column_ = 1;
};

}  // namespace ferry
