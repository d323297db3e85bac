#pragma once
/// What the `pdamp study ...` commands share: their command lines, and the stored study a
/// command names by its id.

#include <boost/program_options.hpp>
#include <cstdint>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "options.hpp"
#include "pdamp/errors.hpp"
#include "pdamp/store/study_store.hpp"
#include "pdamp/study/point_runner.hpp"
#include "pdamp/study/study.hpp"

namespace pdamp {

/// A study subcommand's command line: its own options, --help, --db, and positional
/// arguments in order.
class Subcommand {
 public:
  Subcommand(const std::string& usage, const std::vector<std::string>& positional) : options_(usage) {
    options_.add_options()("help,h", "show this help");
    for (const auto& name : positional) {
      arguments_.add_options()(name.c_str(), boost::program_options::value<std::string>());
      positional_.add(name.c_str(), 1);
    }
    options_.add(db_option());
  }
  boost::program_options::options_description_easy_init add_options() { return options_.add_options(); }
  void add(const boost::program_options::options_description& group) { options_.add(group); }
  /// Parses the arguments; false (with the help printed) for --help.
  bool parse(const std::vector<std::string>& args) {
    boost::program_options::options_description all;
    all.add(options_).add(arguments_);
    vm_ = parse_options(args, all, positional_).vm;
    if (!vm_.count("help")) return true;
    std::cout << options_ << "\n";
    return false;
  }
  const boost::program_options::variables_map& vm() const { return vm_; }

 private:
  boost::program_options::options_description options_;    ///< shown by --help
  boost::program_options::options_description arguments_;  ///< the positional arguments, named in the usage line
  boost::program_options::positional_options_description positional_;
  boost::program_options::variables_map vm_;
};

/// A study's id as given on the command line.
inline std::int64_t parse_study_id(const std::string& text) {
  return parse_whole_number(text, 1, std::numeric_limits<std::int64_t>::max(), "STUDY_ID (see 'pdamp study list')");
}

/// The study of an id in a store, as stored.
struct OpenStudy {
  OpenStudy(const std::string& id_text, const std::string& db, StoreAccess access)
      : id(parse_study_id(id_text)),
        store(db, access),
        studies(store),
        record(find()),
        study(study::stored_study(record)) {}
  /// The study named by STUDY_ID in the --db store.
  OpenStudy(const boost::program_options::variables_map& vm, const std::string& command, StoreAccess access)
      : OpenStudy(required_option(vm, "STUDY_ID", command), vm["db"].as<std::string>(), access) {}

  std::int64_t id;
  RunStore store;
  StudyStore studies;
  StudyRecord record;
  study::Study study;

 private:
  StudyRecord find() {
    auto found = studies.study(id);
    if (!found) {
      throw InputError("study " + std::to_string(id) + " is not in '" + store.file().string() +
                       "' (see 'pdamp study list')");
    }
    return *found;
  }
};

/// Resuming a study: its files, if they are still there, must still describe it (an
/// InputError names every difference); without them, the stored definition is used.
void check_study_files(OpenStudy& open);

}  // namespace pdamp
