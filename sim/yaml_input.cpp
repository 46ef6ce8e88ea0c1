#include "sim/yaml_input.h"

#include <cmath>
#include <cstdlib>
#include <map>
#include <vector>

#include "sim/scene.h"

namespace sim::yaml_input {

int LineOf(const YAML::Node& node) {
  const int line = node.Mark().line;
  return line >= 0 ? line + 1 : 1;
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

void Warn(const std::string& line) { warnings.push_back(line); }

std::vector<std::string> TakeWarnings() {
  std::vector<std::string> out;
  out.swap(warnings);
  return out;
}

}  // namespace sim::yaml_input
