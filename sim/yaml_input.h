// Internal to sim/ (not a public header: it includes yaml-cpp): how sim reads a YAML input file
// (scene, materials, sweep file). One document per file, each map key once, and every fault an
// InputError at the line it is on.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace sim::yaml_input {

// 1-based line of a node, or 1 for a node without a mark (an empty document).
int LineOf(const YAML::Node& node);

// The one document of `text` (a null node for an empty text). A syntax error, or a second document
// that holds anything ("---" then more keys, which a plain YAML::Load would drop silently), is an
// InputError naming `file` and the line.
YAML::Node ParseDocument(const std::string& file, const std::string& text);

// Refuses a key written twice in `map` (yaml-cpp keeps both, and a lookup finds only the first):
// an InputError at the second, naming the first's line. `where` is the map's dotted path ("" at the
// top level). Not a map: nothing to check.
void RefuseDuplicateKeys(const std::string& file, const YAML::Node& map, const std::string& where);

}  // namespace sim::yaml_input
