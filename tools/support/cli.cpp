// Shared CLI11 set-up and error wording (see cli.h).
#include "cli.h"

#include <algorithm>
#include <cstdio>
#include <regex>

namespace pba::tools {

namespace {

// CLI11's layout, with the lowercase "usage:" the tools have always printed
class Formatter final : public CLI::Formatter {
 public:
  std::string make_usage(const CLI::App* app, std::string name) const override {
    std::string s = CLI::Formatter::make_usage(app, std::move(name));
    if (const auto at = s.find("Usage:"); at != std::string::npos) s.replace(at, 6, "usage:");
    return s;
  }
};

// CLI11's wording for a missing value, "X: 1 required TEXT missing", in the tools' words
std::string tidy(const std::string& message) {
  static const std::regex missing(R"(^(\S+): \d+ required \S+ missing$)");
  std::smatch m;
  if (std::regex_match(message, m, missing)) return m[1].str() + ": missing value";
  return message;
}

}  // namespace

const char* version() { return PBA_VERSION; }

void configure_app(CLI::App& app) {
  app.formatter(std::make_shared<Formatter>());
  app.set_version_flag("--version", app.get_name() + " " + PBA_VERSION, "print the version and exit");
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.allow_extras();
  app.get_formatter()->column_width(26);
}

ParseOutcome parse_command_line(CLI::App& app, const std::vector<std::string>& args) {
  ParseOutcome r;
  // CLI11 takes its words last first
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp& e) {
    r.exit = true, r.code = app.exit(e);
    return r;
  } catch (const CLI::CallForVersion& e) {
    r.exit = true, r.code = app.exit(e);
    return r;
  } catch (const CLI::ParseError& e) {
    r.exit = true, r.code = 2, r.error = tidy(e.what());
    return r;
  }
  // words no option took: flags we do not know, or stray positionals
  for (const std::string& w : app.remaining()) {
    r.exit = true, r.code = 2;
    if (!w.empty() && w[0] == '-') r.error = "unknown flag '" + w.substr(0, w.find('=')) + "'";
    else r.error = "unexpected argument '" + w + "'";
    return r;
  }
  return r;
}

}  // namespace pba::tools
