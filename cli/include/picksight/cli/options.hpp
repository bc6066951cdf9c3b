// A tool's command-line options, declared as with CLI11 and parsed by it,
// behind a narrow interface. CLI11 2.1 is header only: a source that
// includes it compiles its parser and validators again, about 8 CPU seconds
// with gcc and more with the sanitizers, in each of the twenty sources that
// declare options. Here CLI11 is compiled once (options.cpp); the sources
// that declare options include only this header.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace CLI {
class App;
class Option;
class Validator;
}  // namespace CLI

namespace picksight::cli {

// A check of an option's value: returns an empty string for a good value,
// otherwise what is wrong (the parser puts the option's name in front). It
// may rewrite the value in place before it is converted.
class Validator {
 public:
  explicit Validator(std::function<std::string(std::string&)> check, std::string description = "");
  // One of CLI11's own (options.cpp: the functions below).
  explicit Validator(std::shared_ptr<const CLI::Validator> validator);

 private:
  friend class Option;
  std::shared_ptr<const CLI::Validator> validator_;
};

// A number in [lo, hi]; the help shows "INT in [lo - hi]" or "FLOAT in ...".
Validator range(int lo, int hi);
Validator range(double lo, double hi);
Validator positiveNumber();
Validator nonNegativeNumber();
Validator existingFile();
Validator existingDirectory();
// One of `names`; the help lists them.
Validator isMember(std::vector<std::string> names);

// One declared option; its App owns it. The setters return the option, so
// that a declaration reads as one chain.
class Option {
 public:
  explicit Option(CLI::Option* option) : option_(option) {}

  Option* check(const Validator& validator);
  // The value's name in the help ("--fps FPS").
  Option* typeName(const std::string& name);
  // The help shows the variable's value at declaration as the default.
  Option* showDefault();
  Option* required();
  // Given only with `other`.
  Option* needs(Option* other);
  // A repeated option adds to the list rather than replacing it.
  Option* takeAll();

 private:
  CLI::Option* option_;
};

// A program's (or a benchmark's) set of options.
class App {
 public:
  App(const std::string& description, const std::string& name);
  App(App&&) noexcept;
  App& operator=(App&&) noexcept;
  ~App();

  // `target` receives the converted value; it must outlive the parse.
  // Defined in options.cpp for the types the tools use (a string, the
  // integer and floating types, lists of strings, numbers).
  template <typename T>
  Option* addOption(const std::string& names, T& target, const std::string& description = "");
  Option* addFlag(const std::string& names, bool& target, const std::string& description = "");
  // "-h,--help" by default; empty names remove the help flag.
  void setHelpFlag(const std::string& names = "", const std::string& description = "");

  // Text the help ends with.
  void footer(const std::string& text);

  const std::string& name() const;
  std::string help() const;

  // Parses `args` (argv without the program name). -h/--help sets *help
  // (when not null) and succeeds, whatever the options require of each other
  // (a value its check refuses is still an error). Returns
  // nothing when parsed, otherwise the error, starting with the option at
  // fault ("--fps: ...", "unknown option '--speed'", "--fps: missing value").
  std::optional<std::string> parse(const std::vector<std::string>& args, bool* help);

  // The long names (without dashes) of the options the last parse was given.
  std::set<std::string> givenOptions() const;
  // What a value of the declared option with this long name ("--fps") is;
  // nothing when no option has the name.
  struct Shape {
    bool flag = false;  // takes no value
    bool list = false;  // takes more than one
  };
  std::optional<Shape> shapeOf(const std::string& name) const;

 private:
  std::unique_ptr<CLI::App> app_;
  std::vector<std::unique_ptr<Option>> options_;
};

}  // namespace picksight::cli
