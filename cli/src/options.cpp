// picksight::cli over CLI11: the one source that compiles CLI11's parser.

#include "picksight/cli/options.hpp"

#include <CLI/CLI.hpp>
#include <cstdint>
#include <iostream>
#include <utility>

#include "picksight/cli/command_line.hpp"

namespace picksight::cli {

Validator::Validator(std::function<std::string(std::string&)> check, std::string description)
    : validator_(std::make_shared<CLI::Validator>(std::move(check), std::move(description))) {}

Validator::Validator(std::shared_ptr<const CLI::Validator> validator)
    : validator_(std::move(validator)) {}

Validator range(int lo, int hi) { return Validator(std::make_shared<CLI::Range>(lo, hi)); }

Validator range(double lo, double hi) { return Validator(std::make_shared<CLI::Range>(lo, hi)); }

Validator positiveNumber() {
  return Validator(std::make_shared<CLI::Validator>(CLI::PositiveNumber));
}

Validator nonNegativeNumber() {
  return Validator(std::make_shared<CLI::Validator>(CLI::NonNegativeNumber));
}

Validator existingFile() { return Validator(std::make_shared<CLI::Validator>(CLI::ExistingFile)); }

Validator existingDirectory() {
  return Validator(std::make_shared<CLI::Validator>(CLI::ExistingDirectory));
}

Validator isMember(std::vector<std::string> names) {
  return Validator(std::make_shared<CLI::IsMember>(std::move(names)));
}

Option* Option::check(const Validator& validator) {
  option_->check(*validator.validator_);
  return this;
}

Option* Option::typeName(const std::string& name) {
  option_->type_name(name);
  return this;
}

Option* Option::showDefault() {
  option_->capture_default_str();
  return this;
}

Option* Option::required() {
  option_->required();
  return this;
}

Option* Option::needs(Option* other) {
  option_->needs(other->option_);
  return this;
}

Option* Option::takeAll() {
  option_->take_all();
  return this;
}

App::App(const std::string& description, const std::string& name)
    : app_(std::make_unique<CLI::App>(description, name)) {}

App::App(App&&) noexcept = default;
App& App::operator=(App&&) noexcept = default;
App::~App() = default;

template <typename T>
Option* App::addOption(const std::string& names, T& target, const std::string& description) {
  options_.push_back(std::make_unique<Option>(app_->add_option(names, target, description)));
  return options_.back().get();
}

// The types the tools and benchmarks bind options to.
template Option* App::addOption(const std::string&, std::string&, const std::string&);
template Option* App::addOption(const std::string&, int&, const std::string&);
template Option* App::addOption(const std::string&, unsigned&, const std::string&);
template Option* App::addOption(const std::string&, unsigned short&, const std::string&);
template Option* App::addOption(const std::string&, long&, const std::string&);
template Option* App::addOption(const std::string&, long long&, const std::string&);
template Option* App::addOption(const std::string&, unsigned long&, const std::string&);
template Option* App::addOption(const std::string&, double&, const std::string&);
template Option* App::addOption(const std::string&, bool&, const std::string&);
template Option* App::addOption(const std::string&, std::vector<std::string>&, const std::string&);
template Option* App::addOption(const std::string&, std::vector<int>&, const std::string&);
template Option* App::addOption(const std::string&, std::vector<double>&, const std::string&);

Option* App::addFlag(const std::string& names, bool& target, const std::string& description) {
  options_.push_back(std::make_unique<Option>(app_->add_flag(names, target, description)));
  return options_.back().get();
}

void App::setHelpFlag(const std::string& names, const std::string& description) {
  app_->set_help_flag(names, description);
}

void App::footer(const std::string& text) { app_->footer(text); }

const std::string& App::name() const { return app_->get_name(); }

std::string App::help() const { return app_->help(); }

std::optional<std::string> App::parse(const std::vector<std::string>& args, bool* help) {
  if (help) *help = false;
  try {
    app_->parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 pops from the back
  } catch (const CLI::CallForHelp&) {
    if (help) *help = true;
    return std::nullopt;
  } catch (const CLI::ExtrasError&) {
    const std::vector<std::string> extras = app_->remaining();
    return "unknown option '" + (extras.empty() ? "" : extras.front()) + "'";
  } catch (const CLI::ArgumentMismatch& e) {
    const std::string what = e.what();
    return what.substr(0, what.find(':')) + ": missing value";
  } catch (const CLI::ParseError& e) {
    return std::string(e.what());
  }
  return std::nullopt;
}

std::set<std::string> App::givenOptions() const {
  std::set<std::string> given;
  for (const CLI::Option* opt : app_->get_options()) {
    if (opt->count() > 0)
      for (const auto& name : opt->get_lnames()) given.insert(name);
  }
  return given;
}

std::optional<App::Shape> App::shapeOf(const std::string& name) const {
  const CLI::Option* option = app_->get_option_no_throw(name);
  if (!option) return std::nullopt;
  // A flag expects no value (its type size is still 1).
  return Shape{option->get_expected_max() == 0, option->get_items_expected_max() > 1};
}

Validator checkValue(std::function<std::string(const std::string&)> check, std::string value_name) {
  return Validator([check = std::move(check)](std::string& value) { return check(value); },
                   std::move(value_name));
}

std::optional<int> parseMainArgs(App& app, int argc, char** argv) {
  bool help = false;
  auto ok = parseArgs(app, std::vector<std::string>(argv + 1, argv + argc), &help);
  if (help) {
    std::cout << app.help();
    return 0;
  }
  if (!ok) {
    std::cerr << app.name() << ": " << ok.error().message << "\n\n" << app.help();
    return 2;
  }
  return std::nullopt;
}

}  // namespace picksight::cli
