#include "urdf_parse.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <exception>
#include <map>
#include <mutex>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/loader/errors.h"

namespace laser_raycast {
namespace {

// Collects what urdfdom reports through console_bridge while it parses: that is the only place
// it says why a parse failed, and it drops a <visual> or <collision> it cannot parse (a "nan" size,
// an empty <geometry>) without failing the parse. Errors are kept; the rest goes on to the
// previous handler. Silent: console_bridge formats and reports nothing while this lives.
class UrdfParseLog : public console_bridge::OutputHandler {
 public:
  explicit UrdfParseLog(bool silent = false)
      : lock_(mutex()),
        previous_(console_bridge::getOutputHandler()),
        previous_level_(console_bridge::getLogLevel()) {
    console_bridge::useOutputHandler(this);
    if (silent) {
      console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
    } else if (previous_level_ > console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      // Errors must reach us even if the application silenced console_bridge.
      console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_ERROR);
    }
  }
  ~UrdfParseLog() override {
    console_bridge::setLogLevel(previous_level_);
    console_bridge::restorePreviousOutputHandler();
  }
  UrdfParseLog(const UrdfParseLog&) = delete;
  UrdfParseLog& operator=(const UrdfParseLog&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char* filename,
           int line) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      errors_.push_back(text);
    } else if (previous_) {
      previous_->log(text, level, filename, line);
    }
  }
  void forward(const std::string& text) const {
    if (previous_ && previous_level_ <= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      previous_->log(text, console_bridge::CONSOLE_BRIDGE_LOG_ERROR, __FILE__, __LINE__);
    }
  }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  // One capture at a time: console_bridge keeps a single previous handler.
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  console_bridge::OutputHandler* previous_;
  console_bridge::LogLevel previous_level_;
  std::vector<std::string> errors_;
};

// More than TinyXML's longest step past a terminator (a UTF-8 sequence, at most 4 bytes, read as
// one character of a name).
constexpr std::size_t kTinyXmlOverread = 16;

// urdfdom's parse of xml, or null with the exception's message added to *errors.
urdf::ModelInterfaceSharedPtr tryParse(const std::string& xml, std::vector<std::string>* errors) {
  try {
    // TinyXML 2.6.2 (under urdfdom) can read a few bytes past the terminator when the text ends
    // inside a UTF-8 sequence in a name (found by test/fuzz/fuzz_urdf_loader under
    // AddressSanitizer): terminators to spare keep those reads inside the buffer.
    return urdf::parseURDF(xml + std::string(kTinyXmlOverread, '\0'));
  } catch (const std::exception& e) {
    errors->push_back(e.what());
    return nullptr;
  }
}

}  // namespace

urdf::ModelInterfaceSharedPtr parseUrdf(const std::string& xml, const std::string& source,
                                        DroppedElements* dropped) {
  urdf::ModelInterfaceSharedPtr model;
  std::vector<std::string> errors;
  // urdfdom hands some of the text it cannot read to console_bridge as the format of its message
  // (an origin's xyz holding "%n" made vsnprintf write through a null pointer: found by
  // test/fuzz/fuzz_urdf_loader). Text with a '%' is therefore parsed with console_bridge silent,
  // and what urdfdom says of it is taken from a second parse of a copy whose '%' are '_', which
  // reads and fails alike: a '%' is never part of a number, and any other text urdfdom only keeps.
  const bool percent = xml.find('%') != std::string::npos;
  if (percent) {
    UrdfParseLog silent(true);
    model = tryParse(xml, &errors);
  }
  UrdfParseLog log;
  if (percent) {
    std::string safe = xml;
    std::replace(safe.begin(), safe.end(), '%', '_');
    std::vector<std::string> unused;
    tryParse(safe, &unused);
  } else {
    model = tryParse(xml, &errors);
  }
  // What urdfdom said came from the copy, whose link names have '_' for '%': each link's own name
  // by its copy's, to file a dropped element under.
  std::map<std::string, std::string> own_name;
  if (percent && model) {
    for (const auto& [name, unused] : model->links_) {
      std::string copy = name;
      std::replace(copy.begin(), copy.end(), '%', '_');
      own_name[copy] = name;
    }
  }
  // urdfdom logs the reasons first, then "Could not parse visual element for Link [name]".
  static const std::regex kDropped(
      "Could not parse (visual|collision) element for Link \\[(.*)\\]");
  std::vector<std::string> reasons;
  for (const std::string& text : log.errors()) {
    std::smatch match;
    if (model && std::regex_search(text, match, kDropped)) {
      std::string why;
      for (const std::string& reason : reasons) why += (why.empty() ? "" : "; ") + reason;
      const auto own = own_name.find(match[2].str());
      const std::string link = own == own_name.end() ? match[2].str() : own->second;
      (*dropped)[{link, match[1].str()}].push_back(why.empty() ? text : why);
      reasons.clear();
    } else {
      reasons.push_back(text);
    }
  }
  if (!model) {
    errors.insert(errors.begin(), reasons.begin(), reasons.end());
    std::string msg = source + ": malformed URDF (urdfdom cannot parse it)";
    for (const std::string& e : errors) msg += "; " + e;
    throw SceneLoadError(msg);
  }
  for (const std::string& text : reasons) log.forward(text);  // not ours to judge
  return model;
}

}  // namespace laser_raycast
