// glint/io/json.hpp: a small JSON reader (the grammar of RFC 8259) for glint's own scene
// files (io/scene_json_read.hpp): a document becomes a tree of JsonValue, each remembering
// its line, so that errors name the file and the line. Numbers are doubles; strings keep
// their escapes decoded (\uXXXX as UTF-8, surrogate pairs included); nesting is limited to
// 256 levels. Every syntax error is a glint::Error "FILE:LINE: what was expected".
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glint/core/error.hpp>

namespace glint {

/// One JSON value and, for arrays and objects, its children. Only the field matching `kind`
/// is meaningful; the others keep their defaults.
struct JsonValue {
    /// The JSON type of a value.
    enum class Kind : std::uint8_t { null, boolean, number, string, array, object };
    Kind kind = Kind::null;  ///< Which of the fields below holds the value.
    bool boolean = false;    ///< The value of `true` or `false` (Kind::boolean).
    double number = 0;       ///< The value of a number, as a double (Kind::number).
    std::string string;      ///< A string's text, escapes decoded to UTF-8 (Kind::string).
    std::vector<JsonValue> items;                            ///< array elements, in file order
    /// Object member names, in file order (duplicates kept; find() returns the first).
    std::vector<std::string> keys;
    /// Object member values, members[i] being the value of keys[i].
    std::vector<JsonValue> members;
    int line = 0;  ///< 1-based line of the value's first character, for error messages.

    /// The member `key` of an object, or nullptr.
    const JsonValue* find(std::string_view key) const {
        for (std::size_t i = 0; i < keys.size(); ++i)
            if (keys[i] == key) return &members[i];
        return nullptr;
    }
};

namespace detail {

class JsonParser {
public:
    JsonParser(std::string_view text, const std::string& file) : s_(text), file_(file) {}

    JsonValue document() {
        JsonValue v = value(0);
        skip();
        if (i_ < s_.size()) fail("text after the end of the document");
        return v;
    }

private:
    [[noreturn]] void fail(const std::string& what) const { throw Error(file_ + ":" + std::to_string(line_) + ": " + what); }

    void skip() {
        while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r'))
            if (s_[i_++] == '\n') ++line_;
    }

    void expect(char c) {
        skip();
        if (i_ >= s_.size() || s_[i_] != c) fail(std::string("expected '") + c + "'");
        ++i_;
    }

    bool word(std::string_view w) {
        if (s_.substr(i_, w.size()) != w) return false;
        i_ += w.size();
        return true;
    }

    JsonValue value(int depth) {
        if (depth > 256) fail("nesting deeper than 256 levels");
        skip();
        if (i_ >= s_.size()) fail("unexpected end of the document");
        JsonValue v;
        v.line = line_;
        const char c = s_[i_];
        if (c == '{') object(v, depth);
        else if (c == '[') array(v, depth);
        else if (c == '"') { v.kind = JsonValue::Kind::string; v.string = string(); }
        else if (word("true")) { v.kind = JsonValue::Kind::boolean; v.boolean = true; }
        else if (word("false")) v.kind = JsonValue::Kind::boolean;
        else if (word("null")) v.kind = JsonValue::Kind::null;
        else { v.kind = JsonValue::Kind::number; v.number = number(); }
        return v;
    }

    void object(JsonValue& v, int depth) {
        v.kind = JsonValue::Kind::object;
        ++i_;
        skip();
        if (i_ < s_.size() && s_[i_] == '}') { ++i_; return; }
        for (;;) {
            skip();
            if (i_ >= s_.size() || s_[i_] != '"') fail("expected a member name in quotes");
            std::string key = string();
            expect(':');
            v.keys.push_back(std::move(key));
            v.members.push_back(value(depth + 1));
            skip();
            if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
            expect('}');
            return;
        }
    }

    void array(JsonValue& v, int depth) {
        v.kind = JsonValue::Kind::array;
        ++i_;
        skip();
        if (i_ < s_.size() && s_[i_] == ']') { ++i_; return; }
        for (;;) {
            v.items.push_back(value(depth + 1));
            skip();
            if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
            expect(']');
            return;
        }
    }

    double number() {
        const std::size_t b = i_;
        while (i_ < s_.size() && (std::string_view("+-.eE0123456789").find(s_[i_]) != std::string_view::npos)) ++i_;
        const std::string t(s_.substr(b, i_ - b));
        char* end = nullptr;
        const double x = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
        if (t.empty() || *end) fail("expected a value, got '" + std::string(s_.substr(b, std::min<std::size_t>(16, s_.size() - b))) + "'");
        return x;
    }

    unsigned hex4() {
        if (i_ + 4 > s_.size()) fail("a \\u escape needs 4 hex digits");
        const std::string h(s_.substr(i_, 4));
        char* end = nullptr;
        const unsigned long u = std::strtoul(h.c_str(), &end, 16);
        if (*end) fail("bad \\u escape '" + h + "'");
        i_ += 4;
        return unsigned(u);
    }

    static void utf8(std::string& out, unsigned cp) {
        if (cp < 0x80) { out += char(cp); return; }
        if (cp < 0x800) { out += char(0xC0 | (cp >> 6)); }
        else if (cp < 0x10000) { out += char(0xE0 | (cp >> 12)); out += char(0x80 | ((cp >> 6) & 0x3F)); }
        else { out += char(0xF0 | (cp >> 18)); out += char(0x80 | ((cp >> 12) & 0x3F)); out += char(0x80 | ((cp >> 6) & 0x3F)); }
        out += char(0x80 | (cp & 0x3F));
    }

    std::string string() {
        ++i_;  // the opening quote
        std::string out;
        for (;;) {
            if (i_ >= s_.size() || s_[i_] == '\n') fail("unterminated string");
            const char c = s_[i_++];
            if (c == '"') return out;
            if (c != '\\') { out += c; continue; }
            if (i_ >= s_.size()) fail("unterminated string");
            const char e = s_[i_++];
            const std::string_view plain = "\"\\/bfnrt", meant = "\"\\/\b\f\n\r\t";
            if (const auto k = plain.find(e); k != std::string_view::npos) { out += meant[k]; continue; }
            if (e != 'u') fail(std::string("bad escape '\\") + e + "'");
            unsigned cp = hex4();
            if (cp >= 0xD800 && cp < 0xDC00 && word("\\u")) cp = 0x10000 + ((cp - 0xD800) << 10) + (hex4() - 0xDC00);
            utf8(out, cp);
        }
    }

    std::string_view s_;
    const std::string& file_;
    std::size_t i_ = 0;
    int line_ = 1;
};

}  // namespace detail

/// Parses a JSON document; `file` names it in errors.
inline JsonValue parse_json(std::string_view text, const std::string& file) {
    return detail::JsonParser(text, file).document();
}

}  // namespace glint
