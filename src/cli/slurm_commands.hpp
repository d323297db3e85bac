#pragma once
/// `pdamp study submit|collect|status|task`: studies on a Slurm cluster.

#include <string>
#include <vector>

namespace pdamp {

int study_submit(const std::vector<std::string>& args);
int study_collect(const std::vector<std::string>& args);
int study_status(const std::vector<std::string>& args);
int study_task(const std::vector<std::string>& args);

}  // namespace pdamp
