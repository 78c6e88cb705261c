#pragma once
// A strict JSON parser for tests: what netlab prints with --json must parse, whole.

#include <cctype>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace netlab::testing {

struct Json {
  using Array = std::vector<Json>;
  using Object = std::map<std::string, Json>;
  std::variant<std::nullptr_t, bool, double, std::string, Array, Object> value;

  bool is_null() const { return std::holds_alternative<std::nullptr_t>(value); }
  double number() const { return std::get<double>(value); }
  bool boolean() const { return std::get<bool>(value); }
  const std::string& string() const { return std::get<std::string>(value); }
  const Array& array() const { return std::get<Array>(value); }
  const Object& object() const { return std::get<Object>(value); }
  bool has(const std::string& key) const { return object().count(key) > 0; }
  const Json& operator[](const std::string& key) const {
    const auto it = object().find(key);
    if (it == object().end()) throw std::out_of_range("no key " + key);
    return it->second;
  }
};

class JsonParser {
 public:
  // Parses exactly one JSON value (surrounding whitespace allowed); throws on anything else.
  static Json Parse(const std::string& text) {
    JsonParser p(text);
    Json v = p.Value();
    p.SkipSpace();
    if (p.pos_ != text.size()) p.Fail("trailing characters");
    return v;
  }

 private:
  explicit JsonParser(const std::string& text) : text_(text) {}

  [[noreturn]] void Fail(const std::string& what) const {
    throw std::runtime_error("JSON: " + what + " at offset " + std::to_string(pos_));
  }
  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  char Peek() {
    SkipSpace();
    if (pos_ >= text_.size()) Fail("unexpected end");
    return text_[pos_];
  }
  void Expect(char c) {
    if (Peek() != c) Fail(std::string("expected '") + c + "'");
    ++pos_;
  }
  bool Literal(const char* word) {
    const std::string w(word);
    if (text_.compare(pos_, w.size(), w) == 0) {
      pos_ += w.size();
      return true;
    }
    return false;
  }
  Json Value() {
    const char c = Peek();
    if (c == '{') return Object();
    if (c == '[') return Array();
    if (c == '"') return Json{String()};
    if (Literal("true")) return Json{true};
    if (Literal("false")) return Json{false};
    if (Literal("null")) return Json{nullptr};
    return Json{Number()};
  }
  Json Object() {
    Expect('{');
    Json::Object object;
    if (Peek() == '}') {
      ++pos_;
      return Json{object};
    }
    while (true) {
      if (Peek() != '"') Fail("expected a key");
      const std::string key = String();
      Expect(':');
      if (object.count(key)) Fail("duplicate key " + key);
      object[key] = Value();
      if (Peek() == ',') {
        ++pos_;
        continue;
      }
      Expect('}');
      return Json{object};
    }
  }
  Json Array() {
    Expect('[');
    Json::Array array;
    if (Peek() == ']') {
      ++pos_;
      return Json{array};
    }
    while (true) {
      array.push_back(Value());
      if (Peek() == ',') {
        ++pos_;
        continue;
      }
      Expect(']');
      return Json{array};
    }
  }
  std::string String() {
    Expect('"');
    std::string out;
    while (pos_ < text_.size() && text_[pos_] != '"') {
      char c = text_[pos_++];
      if (static_cast<unsigned char>(c) < 0x20) Fail("control character in string");
      if (c == '\\') {
        if (pos_ >= text_.size()) Fail("bad escape");
        const char e = text_[pos_++];
        switch (e) {
          case '"': out += '"'; break;
          case '\\': out += '\\'; break;
          case '/': out += '/'; break;
          case 'n': out += '\n'; break;
          case 'r': out += '\r'; break;
          case 't': out += '\t'; break;
          case 'b': out += '\b'; break;
          case 'f': out += '\f'; break;
          case 'u': {
            if (pos_ + 4 > text_.size()) Fail("bad \\u escape");
            out += static_cast<char>(std::stoi(text_.substr(pos_, 4), nullptr, 16));
            pos_ += 4;
            break;
          }
          default: Fail("bad escape");
        }
      } else {
        out += c;
      }
    }
    Expect('"');
    return out;
  }
  double Number() {
    const char* begin = text_.c_str() + pos_;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin) Fail("expected a value");
    // JSON has no nan/inf/hex.
    for (const char* p = begin; p < end; ++p)
      if (!(std::isdigit(static_cast<unsigned char>(*p)) || *p == '-' || *p == '+' || *p == '.' ||
            *p == 'e' || *p == 'E'))
        Fail("not a JSON number");
    pos_ += end - begin;
    return v;
  }

  const std::string& text_;
  size_t pos_ = 0;
};

}  // namespace netlab::testing
