#include <algorithm>
#include <cctype>
#include <string_view>

#include "arm/internal_urdf_text.h"

namespace arm {
namespace {

constexpr size_t kNone = std::string::npos;

bool IsWord(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool IsSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

// One tag: '<' [space] ['/'] NAME ATTRIBUTES ['/'] '>' ('>' missing at the end of the text).
struct Tag {
  size_t begin = 0;           // its '<'
  size_t end = 0;             // past its '>'
  std::string_view name;      // "" for <?...?> and <!...>
  size_t attributes = 0;      // [attributes, attributes_end): what follows the name
  size_t attributes_end = 0;  // its '>'
  bool closing = false;       // </NAME>
  bool self_closing = false;  // <NAME .../>
};

// Calls on_tag(tag) for each tag of v[from, v.size()) in order, comments skipped, until it
// returns false. Every character is read once: quoted values are skipped whole (a '>' in one
// does not end the tag).
template <typename F>
void ForEachTag(std::string_view v, size_t from, F&& on_tag) {
  size_t at = from;
  while (at < v.size()) {
    Tag tag;
    tag.begin = v.find('<', at);
    if (tag.begin == kNone) return;
    if (v.compare(tag.begin, 4, "<!--") == 0) {
      const size_t close = v.find("-->", tag.begin + 4);
      at = close == kNone ? v.size() : close + 3;
      continue;
    }
    size_t p = tag.begin + 1;
    while (p < v.size() && IsSpace(v[p])) ++p;
    if (p < v.size() && v[p] == '/') {
      tag.closing = true;
      ++p;
    }
    const size_t name = p;
    while (p < v.size() && IsWord(v[p])) ++p;
    tag.name = v.substr(name, p - name);
    tag.attributes = p;
    while (p < v.size() && v[p] != '>') {
      if (v[p] == '"' || v[p] == '\'') {
        const size_t close = v.find(v[p], p + 1);
        p = close == kNone ? v.size() : close + 1;
      } else {
        ++p;
      }
    }
    tag.attributes_end = p;
    tag.self_closing = p > tag.attributes && v[p - 1] == '/';
    tag.end = std::min(p + 1, v.size());
    if (!on_tag(tag)) return;
    at = tag.end;
  }
}

// Calls on_attribute(name, value) for each NAME="VALUE" (or 'VALUE') of a tag's attributes.
template <typename F>
void ForEachAttribute(std::string_view v, const Tag& tag, F&& on_attribute) {
  const size_t to = tag.attributes_end;
  size_t p = tag.attributes;
  while (p < to) {
    if (IsSpace(v[p]) || v[p] == '/') {
      ++p;
      continue;
    }
    const size_t name = p;
    while (p < to && !IsSpace(v[p]) && v[p] != '=' && v[p] != '/') ++p;
    const std::string_view attribute = v.substr(name, p - name);
    while (p < to && IsSpace(v[p])) ++p;
    if (p >= to || v[p] != '=') continue;
    ++p;
    while (p < to && IsSpace(v[p])) ++p;
    if (p >= to || (v[p] != '"' && v[p] != '\'')) continue;
    const char quote = v[p++];
    const size_t value = p;
    while (p < to && v[p] != quote) ++p;
    on_attribute(attribute, v.substr(value, p - value));
    ++p;
  }
}

}  // namespace

UrdfIndex::UrdfIndex(const std::string& text) {
  const std::string_view v(text);
  std::map<std::string_view, std::vector<size_t>> open;  // tag -> elements_ not yet closed
  int line = 1;
  size_t counted = 0;  // the newlines before here are in `line`
  ForEachTag(v, 0, [&](const Tag& tag) {
    line += static_cast<int>(std::count(v.begin() + static_cast<std::ptrdiff_t>(counted),
                                        v.begin() + static_cast<std::ptrdiff_t>(tag.begin), '\n'));
    counted = tag.begin;
    if (tag.name.empty()) return true;
    if (tag.closing) {
      std::vector<size_t>& pending = open[tag.name];
      if (!pending.empty()) {
        if (pending.back() != kNone) elements_[pending.back()].end = tag.end;
        pending.pop_back();
      }
      return true;
    }
    size_t index = kNone;
    ForEachAttribute(v, tag, [&](std::string_view attribute, std::string_view value) {
      if (attribute != "name" || index != kNone) return;
      index = elements_.size();
      elements_.push_back({tag.begin, tag.self_closing ? tag.end : text.size(), line});
      first_.emplace(std::make_pair(std::string(tag.name), std::string(value)), index);
    });
    if (!tag.self_closing) open[tag.name].push_back(index);
    return true;
  });
}

int UrdfIndex::Line(const std::string& tag, const std::string& name) const {
  const auto it = first_.find({tag, name});
  return it == first_.end() ? 0 : elements_[it->second].line;
}

std::pair<size_t, size_t> UrdfIndex::Span(const std::string& tag, const std::string& name) const {
  const auto it = first_.find({tag, name});
  if (it == first_.end()) return {kNone, kNone};
  return {elements_[it->second].begin, elements_[it->second].end};
}

std::string AttributeIn(const std::string& text, size_t begin, size_t end, const std::string& child,
                        const std::string& attr) {
  std::string found;
  bool done = false;
  ForEachTag(std::string_view(text).substr(0, std::min(end, text.size())), begin,
             [&](const Tag& tag) {
               if (tag.closing || tag.name != child) return true;
               ForEachAttribute(text, tag, [&](std::string_view attribute, std::string_view value) {
                 if (done || attribute != attr) return;
                 found = std::string(value);
                 done = true;
               });
               return !done;
             });
  return found;
}

}  // namespace arm
