#include "config/yaml_documents.h"

#include <yaml-cpp/eventhandler.h>

#include <sstream>

namespace hapticd::config {
namespace {

// Remembers where each document starts; the parser's events carry nothing else we need.
class DocumentStarts final : public YAML::EventHandler {
 public:
  YAML::Mark last;
  void OnDocumentStart(const YAML::Mark& mark) override { last = mark; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

// Throws when a document starts where the previous one did: the parser is stuck there.
void refuse_stuck_parser(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentStarts starts;
  int previous = -1;
  while (parser.HandleNextDocument(starts)) {
    if (starts.last.pos <= previous) {
      const auto at = static_cast<std::size_t>(starts.last.pos);
      const std::string what = at < text.size() ? std::string(1, text[at]) : std::string("end");
      throw YAML::ParserException(starts.last,
                                  "unexpected '" + what + "': the YAML parser cannot get past it");
    }
    previous = starts.last.pos;
  }
}

}  // namespace

std::vector<YAML::Node> load_yaml_documents(const std::string& text) {
  refuse_stuck_parser(text);
  return YAML::LoadAll(text);
}

}  // namespace hapticd::config
