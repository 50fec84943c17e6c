#include "io/pbrt/pbrt_tokenizer.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ferry {
namespace {

using Kind = PbrtToken::Kind;

std::vector<PbrtToken> tokenize(const std::string& text) {
  PbrtTokenizer t(ByteStream::fromMemory(text, "test.pbrt"));
  std::vector<PbrtToken> out;
  for (;;) {
    const PbrtToken& tok = t.next();
    out.push_back(tok);
    if (tok.kind == Kind::End) break;
  }
  return out;
}

InputError tokenizeError(const std::string& text) {
  try {
    tokenize(text);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for: " << text;
  return InputError("none");
}

TEST(PbrtTokenizer, KindsLinesAndColumns) {
  auto t = tokenize(
      "Shape \"sphere\"\n  \"float radius\" [ 2.5 -1e3 ]  # comment \"not a string\n\tWorldEnd");
  ASSERT_EQ(t.size(), 9u);
  EXPECT_EQ(t[0].kind, Kind::Word);
  EXPECT_EQ(t[0].text, "Shape");
  EXPECT_EQ(t[0].line, 1);
  EXPECT_EQ(t[0].column, 1);
  EXPECT_EQ(t[1].kind, Kind::String);
  EXPECT_EQ(t[1].text, "sphere");
  EXPECT_EQ(t[1].column, 7);
  EXPECT_EQ(t[2].text, "float radius");
  EXPECT_EQ(t[2].line, 2);
  EXPECT_EQ(t[2].column, 3);
  EXPECT_EQ(t[3].kind, Kind::OpenBracket);
  EXPECT_EQ(t[4].text, "2.5");
  EXPECT_TRUE(t[4].isNumber());
  EXPECT_EQ(t[5].text, "-1e3");
  EXPECT_TRUE(t[5].isNumber());
  EXPECT_EQ(t[6].kind, Kind::CloseBracket);
  EXPECT_EQ(t[7].text, "WorldEnd");
  EXPECT_FALSE(t[7].isNumber());
  EXPECT_EQ(t[7].line, 3);
  EXPECT_EQ(t[7].column, 2);
  EXPECT_EQ(t[8].kind, Kind::End);
}

TEST(PbrtTokenizer, BracketsEndWordsAndNumbers) {
  auto t = tokenize("[1 2]\"a\"[\"b\"]");
  ASSERT_EQ(t.size(), 9u);
  EXPECT_EQ(t[0].kind, Kind::OpenBracket);
  EXPECT_EQ(t[1].text, "1");
  EXPECT_EQ(t[2].text, "2");
  EXPECT_EQ(t[3].kind, Kind::CloseBracket);
  EXPECT_EQ(t[4].text, "a");
  EXPECT_EQ(t[5].kind, Kind::OpenBracket);
  EXPECT_EQ(t[6].text, "b");
  EXPECT_EQ(t[7].kind, Kind::CloseBracket);
}

TEST(PbrtTokenizer, EscapesAndSpacesInStrings) {
  auto t = tokenize("\"a file\\twith \\\"quotes\\\" and \\\\ back.png\"");
  EXPECT_EQ(t[0].text, "a file\twith \"quotes\" and \\ back.png");
}

TEST(PbrtTokenizer, ByteOrderMarkAndCrLf) {
  auto t = tokenize("\xEF\xBB\xBFWorldBegin\r\nShape");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].text, "WorldBegin");
  EXPECT_EQ(t[1].text, "Shape");
  EXPECT_EQ(t[1].line, 2);
}

TEST(PbrtTokenizer, PeekDoesNotConsume) {
  PbrtTokenizer t(ByteStream::fromMemory("A B", "x"));
  EXPECT_EQ(t.peek().text, "A");
  EXPECT_EQ(t.peek().text, "A");
  EXPECT_EQ(t.next().text, "A");
  EXPECT_EQ(t.next().text, "B");
  EXPECT_EQ(t.next().kind, Kind::End);
  EXPECT_EQ(t.next().kind, Kind::End);
}

TEST(PbrtTokenizer, LongCommentsAcrossBuffers) {
  std::string text = "# " + std::string(200000, 'x') + "\nWorldBegin";
  auto t = tokenize(text);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].text, "WorldBegin");
  EXPECT_EQ(t[0].line, 2);
}

TEST(PbrtTokenizer, Errors) {
  struct Case {
    std::string text;
    int line, column;
    std::string contains;
  };
  for (const Case& c : std::vector<Case>{
           {"Shape \"sphere", 1, 7, "string never closed"},
           {"Shape \"sph\nere\"", 1, 7, "not closed before the end of its line"},
           {"Texture \"a\\qb\"", 1, 11, "unknown escape '\\q'"},
           {"WorldBegin\n\x01", 2, 1, "unexpected byte 0x01"},
           {std::string("Shape \"a\0b\"", 11), 1, 9, "NUL byte inside a string"},
           {"Wor\x02ld", 1, 4, "unexpected byte 0x02"},
       }) {
    InputError e = tokenizeError(c.text);
    SCOPED_TRACE(e.what());
    EXPECT_EQ(e.where().file, "test.pbrt");
    EXPECT_EQ(e.where().line, c.line);
    EXPECT_EQ(e.where().column, c.column);
    EXPECT_NE(std::string(e.what()).find(c.contains), std::string::npos);
  }
}

TEST(PbrtTokenizer, UnboundedStringIsAnError) {
  std::string text = "\"" + std::string((size_t(1) << 20) + 10, 'a') + "\"";
  InputError e = tokenizeError(text);
  EXPECT_NE(std::string(e.what()).find("longer than 1 MiB"), std::string::npos);
}

}  // namespace
}  // namespace ferry
