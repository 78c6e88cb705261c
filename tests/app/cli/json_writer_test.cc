#include "app/cli/json_writer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/app/cli/json_parse.h"

namespace netlab::app {
namespace {

using netlab::testing::JsonParser;

TEST(JsonWriter, NestedObjectsAndArraysParseBack) {
  JsonWriter w;
  w.BeginObject();
  w.Key("a").Int(1);
  w.Key("b").BeginArray().Number(0.5).Bool(true).Null().EndArray();
  w.Key("c").BeginObject().Key("d").String("x").EndObject();
  w.Key("e").BeginArray().EndArray();
  w.Key("f").Vector3(std::array<double, 3>{1, 2, 3});
  w.EndObject();
  const auto v = JsonParser::Parse(w.str());
  EXPECT_EQ(v["a"].number(), 1.0);
  EXPECT_EQ(v["b"].array().size(), 3u);
  EXPECT_TRUE(v["b"].array()[2].is_null());
  EXPECT_EQ(v["c"]["d"].string(), "x");
  EXPECT_TRUE(v["e"].array().empty());
  EXPECT_EQ(v["f"].array()[2].number(), 3.0);
}

TEST(JsonWriter, StringsAreEscaped) {
  JsonWriter w;
  w.BeginObject().Key("quote\"key").String("line\nbreak\\ \"q\" \x01").EndObject();
  const auto v = JsonParser::Parse(w.str());
  EXPECT_EQ(v["quote\"key"].string(), "line\nbreak\\ \"q\" \x01");
}

TEST(JsonWriter, NonFiniteNumbersBecomeNull) {
  JsonWriter w;
  w.BeginArray().Number(std::nan("")).Number(INFINITY).Number(1e-300).EndArray();
  const auto v = JsonParser::Parse(w.str());
  EXPECT_TRUE(v.array()[0].is_null());
  EXPECT_TRUE(v.array()[1].is_null());
  EXPECT_EQ(v.array()[2].number(), 1e-300);
}

TEST(JsonParser, RejectsMalformedText) {
  EXPECT_THROW(JsonParser::Parse("{,\"a\":1}"), std::runtime_error);
  EXPECT_THROW(JsonParser::Parse("{\"a\":1,,\"b\":2}"), std::runtime_error);
  EXPECT_THROW(JsonParser::Parse("[1 2]"), std::runtime_error);
  EXPECT_THROW(JsonParser::Parse("{\"a\":nan}"), std::runtime_error);
  EXPECT_THROW(JsonParser::Parse("{} x"), std::runtime_error);
}

}  // namespace
}  // namespace netlab::app
