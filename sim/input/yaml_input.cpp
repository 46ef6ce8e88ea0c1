#include "sim/input/yaml_input.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <vector>

#include "sim/input/input_error.h"

namespace sim::yaml_input {

int LineOf(const YAML::Node& node) {
  const int line = node.Mark().line;
  return line >= 0 ? line + 1 : 1;
}

std::string Describe(const YAML::Node& node) {
  // A key looked up in a const map where it is not: an invalid node, whose Type() throws.
  if (!node.IsDefined()) return "nothing (key missing)";
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return node.Scalar().empty() ? "an empty string" : node.Scalar();
    case YAML::NodeType::Sequence: {
      std::string out = "[";
      for (size_t i = 0; i < node.size(); ++i) {
        if (i > 0) out += ", ";
        const YAML::Node item = node[i];
        out += item.IsScalar() ? item.Scalar() : (item.IsMap() ? "{...}" : Describe(item));
      }
      return out + "]";
    }
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Undefined:
    default:
      return "nothing (key missing)";
  }
}

std::string ResolveAgainst(const std::string& owner_file, const std::string& name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return name;
  return (std::filesystem::path(owner_file).parent_path() / p).string();
}

YAML::Node ParseDocument(const std::string& file, const std::string& text) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(text);
  } catch (const YAML::ParserException& e) {
    const int line = e.mark.line >= 0 ? e.mark.line + 1 : 1;
    throw InputError(file, line, "syntax", "valid YAML", "a syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    const int line = e.mark.line >= 0 ? e.mark.line + 1 : 1;
    throw InputError(file, line, "syntax", "valid YAML", "an error: " + e.msg);
  }
  for (size_t k = 1; k < documents.size(); ++k) {
    // A bare "---" or "..." at the end leaves an empty document: harmless, nothing is dropped.
    if (documents[k].IsNull()) continue;
    throw InputError(file, LineOf(documents[k]), "(document " + std::to_string(k + 1) + ")",
                     "one YAML document", "a second one after '---'",
                     "it would be ignored; join it to the first or put it in its own file");
  }
  return documents.empty() ? YAML::Node() : documents.front();
}

void RefuseDuplicateKeys(const std::string& file, const YAML::Node& map, const std::string& where) {
  if (!map.IsMap()) return;
  std::map<std::string, int> seen;  // key -> line
  for (auto it = map.begin(); it != map.end(); ++it) {
    std::string key;
    if (it->first.IsScalar()) {
      key = it->first.Scalar();
    } else {
      YAML::Emitter e;
      e << YAML::Flow << it->first;
      key = e.c_str();
    }
    const auto [first, inserted] = seen.emplace(key, LineOf(it->first));
    if (!inserted) {
      throw InputError(file, LineOf(it->first), where.empty() ? key : where + "." + key,
                       "each key once", "a second '" + key + "'",
                       "first at line " + std::to_string(first->second));
    }
  }
}

bool ParseAngleWithUnit(const std::string& text, bool rate, double* degrees) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(v)) return false;
  std::string unit(end);
  unit.erase(0, unit.find_first_not_of(" \t"));
  unit.erase(unit.find_last_not_of(" \t") + 1);
  if (unit.size() == std::string(end).size()) return false;  // no space before the unit
  const double kDegPerRad = 180.0 / 3.14159265358979323846;
  if (unit == (rate ? "deg/s" : "deg")) {
    *degrees = v;
  } else if (unit == (rate ? "rad/s" : "rad")) {
    *degrees = v * kDegPerRad;
  } else {
    return false;
  }
  return true;
}

bool LooksLikeRadians(double v) {
  return v != std::floor(v) && std::abs(v) <= 2 * 3.14159265358979323846;
}

namespace {
thread_local std::vector<std::string> warnings;
}  // namespace

void Warn(const std::string& file, int line, const std::string& text) {
  warnings.push_back(file + ":" + std::to_string(line) + ": " + text);
}

std::vector<std::string> TakeWarnings() {
  std::vector<std::string> out;
  out.swap(warnings);
  return out;
}

namespace {

[[noreturn]] void BadSet(const std::string& set, const std::string& expected) {
  throw InputError("--set", 0, "", expected, "'" + set + "'");
}

// `text` parsed so that its nodes carry `line` (1-based).
YAML::Node ParseAtLine(const std::string& text, int line) {
  return YAML::Load(std::string(static_cast<size_t>(line - 1), '\n') + text);
}

}  // namespace

std::string TextWithSets(const std::string& text, const std::vector<std::string>& sets) {
  std::string out = text;
  for (const std::string& set : sets) {
    if (set.find_first_of("\r\n") != std::string::npos) BadSet(set, "KEY=VALUE on one line");
    if (!out.empty() && out.back() != '\n') out += '\n';
    out += kSetComment + set + '\n';
  }
  return out;
}

std::vector<std::string> SetsOf(const std::string& text) {
  std::vector<std::string> sets;
  const std::string marker = std::string("\n") + kSetComment;
  for (size_t at = text.find(marker); at != std::string::npos; at = text.find(marker, at + 1)) {
    const size_t begin = at + marker.size();
    const size_t end = std::min(text.find('\n', begin), text.size());
    sets.push_back(text.substr(begin, end - begin));
  }
  return sets;
}

void ApplySets(YAML::Node* root, const std::vector<std::string>& sets) {
  for (size_t i = 0; i < sets.size(); ++i) {
    const std::string& set = sets[i];
    const int line = kSetLine + static_cast<int>(i);
    const std::string expected = "KEY=VALUE with KEY a dotted scene key (dig.bite_depth)";
    const size_t eq = set.find('=');
    if (eq == std::string::npos || eq == 0) BadSet(set, expected);
    std::vector<std::string> keys;
    for (size_t begin = 0; begin <= eq;) {
      const size_t dot = std::min(set.find('.', begin), eq);
      const std::string key = set.substr(begin, dot - begin);
      if (key.empty()) BadSet(set, expected);
      for (char c : key)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-')
          BadSet(set, expected);
      keys.push_back(key);
      begin = dot + 1;
    }
    YAML::Node value;
    try {
      value = ParseAtLine(set.substr(eq + 1), line);
    } catch (const YAML::Exception& e) {
      throw InputError("--set " + set, 0, set.substr(0, eq), "a YAML value",
                       "a syntax error: " + e.msg);
    }
    if (!root->IsMap() && !root->IsNull()) BadSet(set, "a scene whose top level is a map");
    if (root->IsNull()) *root = ParseAtLine("{}", line);
    // Down the path: a list index into a list, else a map key (a map made where it is missing).
    YAML::Node node = *root;
    for (size_t k = 0; k < keys.size(); ++k) {
      const std::string& key = keys[k];
      const bool last = k + 1 == keys.size();
      if (node.IsSequence()) {
        const bool digits = key.find_first_not_of("0123456789") == std::string::npos;
        const size_t index = digits && key.size() < 9 ? std::stoul(key) : node.size();
        if (index >= node.size()) {
          BadSet(set, "an index below " + std::to_string(node.size()) + " at '" + key + "'");
        }
        if (last && value.IsNull()) BadSet(set, "a value (a list entry cannot be removed)");
        if (last) {
          node[index] = value;
        } else {
          node.reset(node[index]);
        }
        continue;
      }
      if (!node.IsMap()) BadSet(set, "a map or a list above '" + key + "'");
      // (A lookup on a const node: a non-const one would insert the key, undefined.)
      const YAML::Node found = static_cast<const YAML::Node&>(node)[key];
      const bool present = found.IsDefined();
      if (last && value.IsNull()) {
        node.remove(key);
      } else if (last) {
        if (present) {
          node[key] = value;
        } else {
          node[ParseAtLine(key, line)] = value;
        }
      } else {
        if (!present || !(found.IsMap() || found.IsSequence())) {
          if (present) {
            node[key] = ParseAtLine("{}", line);
          } else {
            node[ParseAtLine(key, line)] = ParseAtLine("{}", line);
          }
        }
        node.reset(node[key]);
      }
    }
  }
}

std::string SetAt(int line, const std::vector<std::string>& sets) {
  const int i = line - kSetLine;
  return i >= 0 && i < static_cast<int>(sets.size()) ? sets[i] : std::string();
}

std::string WarningNamingSet(const std::string& warning, const std::string& file,
                             const std::vector<std::string>& sets) {
  for (size_t i = 0; i < sets.size(); ++i) {
    const std::string at = file + ":" + std::to_string(kSetLine + static_cast<int>(i)) + ": ";
    if (warning.compare(0, at.size(), at) == 0)
      return "--set " + sets[i] + ": " + warning.substr(at.size());
  }
  return warning;
}

}  // namespace sim::yaml_input
