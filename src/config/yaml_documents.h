// Every YAML document in a text, parsed by yaml-cpp, without yaml-cpp 0.7's endless loop.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace hapticd::config {

// YAML::LoadAll, except that a text on which yaml-cpp's parser stops making progress (a
// stray ',' at the start of a document: yaml-cpp 0.7 then yields empty documents forever,
// allocating each one, until memory runs out) is a YAML::ParserException naming the line
// and column of the character it cannot get past. Found by fuzz/ (set_override, config_gate).
// Not RT-safe: parses and allocates.
std::vector<YAML::Node> load_yaml_documents(const std::string& text);

}  // namespace hapticd::config
