#include "io/pbrt/pbrt_tokenizer.h"

#include <fmt/format.h>

namespace ferry {
namespace {

constexpr size_t kMaxToken = size_t(1) << 20;

bool isSpace(int c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

// Ends a word: whitespace, a quote, a bracket or a comment.
bool endsWord(int c) {
  return c < 0 || isSpace(c) || c == '"' || c == '[' || c == ']' || c == '#';
}

}  // namespace

bool PbrtToken::isNumber() const {
  if (kind != Kind::Word || text.empty()) return false;
  char c = text[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

PbrtTokenizer::PbrtTokenizer(ByteStream stream) : stream_(std::move(stream)) {
  // A UTF-8 byte order mark is not part of the first directive.
  std::string_view head = stream_.buffered();
  if (head.size() >= 3 && head.substr(0, 3) == "\xEF\xBB\xBF") stream_.consume(3);
}

void PbrtTokenizer::fail(int line, int column, const std::string& message) const {
  throw InputError(SourceLocation{stream_.name(), line, column}, message);
}

const PbrtToken& PbrtTokenizer::next() {
  if (hasLookahead_) {
    std::swap(current_, lookahead_);
    hasLookahead_ = false;
  } else {
    scan(current_);
  }
  return current_;
}

const PbrtToken& PbrtTokenizer::peek() {
  if (!hasLookahead_) {
    scan(lookahead_);
    hasLookahead_ = true;
  }
  return lookahead_;
}

void PbrtTokenizer::scan(PbrtToken& token) {
  token.text.clear();
  // Whitespace and comments, a buffer at a time.
  for (;;) {
    std::string_view b = stream_.buffered();
    size_t i = 0;
    while (i < b.size() && isSpace(static_cast<unsigned char>(b[i]))) {
      if (b[i] == '\n') {
        ++line_;
        column_ = 1;
      } else {
        ++column_;
      }
      ++i;
    }
    stream_.consume(i);
    if (i < b.size() || b.empty()) break;
  }
  for (;;) {
    int c = stream_.peek();
    if (c < 0) {
      token.kind = PbrtToken::Kind::End;
      token.line = line_;
      token.column = column_;
      return;
    }
    if (c == '\n') {
      stream_.get();
      ++line_;
      column_ = 1;
    } else if (isSpace(c)) {
      stream_.get();
      ++column_;
    } else if (c == '#') {
      // Skip to the end of the line, a buffer at a time.
      for (;;) {
        std::string_view rest = stream_.buffered();
        if (rest.empty()) break;
        size_t newline = rest.find('\n');
        if (newline == std::string_view::npos) {
          stream_.consume(rest.size());
          continue;
        }
        stream_.consume(newline);
        break;
      }
    } else {
      break;
    }
  }

  token.line = line_;
  token.column = column_;
  int c = stream_.get();
  ++column_;
  if (c == '[') {
    token.kind = PbrtToken::Kind::OpenBracket;
    return;
  }
  if (c == ']') {
    token.kind = PbrtToken::Kind::CloseBracket;
    return;
  }
  if (c == '"') {
    token.kind = PbrtToken::Kind::String;
    for (;;) {
      int d = stream_.get();
      ++column_;
      if (d < 0) fail(token.line, token.column, "string never closed: the file ends inside it");
      if (d == '"') return;
      if (d == '\n' || d == '\r')
        fail(token.line, token.column, "string not closed before the end of its line");
      if (d == '\\') {
        int e = stream_.get();
        ++column_;
        switch (e) {
          case 'b':
            d = '\b';
            break;
          case 'f':
            d = '\f';
            break;
          case 'n':
            d = '\n';
            break;
          case 'r':
            d = '\r';
            break;
          case 't':
            d = '\t';
            break;
          case '\\':
            d = '\\';
            break;
          case '\'':
            d = '\'';
            break;
          case '"':
            d = '"';
            break;
          default:
            if (e < 0)
              fail(token.line, token.column, "string never closed: the file ends inside it");
            fail(line_, column_ - 2,
                 e >= 32 && e < 127 ? fmt::format("unknown escape '\\{}' in a string", char(e))
                                    : fmt::format("unknown escape (byte 0x{:02x}) in a string", e));
        }
      } else if (d == 0) {
        fail(line_, column_ - 1, "NUL byte inside a string: this is not a text file");
      }
      if (token.text.size() >= kMaxToken)
        fail(token.line, token.column, "string longer than 1 MiB (a missing closing quote?)");
      token.text.push_back(char(d));
    }
  }
  if (c < 32 || c == 127) {
    fail(token.line, token.column,
         fmt::format("unexpected byte 0x{:02x}: this is not a pbrt text file", c));
  }
  token.kind = PbrtToken::Kind::Word;
  token.text.push_back(char(c));
  for (;;) {
    std::string_view b = stream_.buffered();
    size_t i = 0;
    while (i < b.size()) {
      int d = static_cast<unsigned char>(b[i]);
      if (endsWord(d)) break;
      if (d < 32 || d == 127)
        fail(line_, column_ + int(i),
             fmt::format("unexpected byte 0x{:02x}: this is not a pbrt text file", d));
      ++i;
    }
    if (token.text.size() + i > kMaxToken) fail(token.line, token.column, "word longer than 1 MiB");
    token.text.append(b.data(), i);
    column_ += int(i);
    stream_.consume(i);
    if (i < b.size() || b.empty()) break;
  }
}

}  // namespace ferry
