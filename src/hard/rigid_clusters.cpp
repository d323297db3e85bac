#include "hard/rigid_clusters.hpp"

#include <utility>

namespace pdamp::hard {

RigidClusters::RigidClusters(int particle_count, double speed_m_s)
    : speed_m_s_(speed_m_s),
      cluster_(static_cast<std::size_t>(particle_count), -1),
      place_(static_cast<std::size_t>(particle_count), 0) {}

std::span<const int> RigidClusters::join(int i, int j) {
  ++joins_;
  int into = cluster_[i], from = cluster_[j];
  if (into < 0) {
    if (unused_.empty()) {
      into = static_cast<int>(members_.size());
      members_.emplace_back();
    } else {
      into = unused_.back();
      unused_.pop_back();
    }
    cluster_[i] = into;
    place_[i] = 0;
    members_[static_cast<std::size_t>(into)].push_back(i);
  }
  std::vector<int>& joined = members_[static_cast<std::size_t>(into)];
  const auto add = [&](int k) {
    cluster_[k] = into;
    place_[k] = static_cast<int>(joined.size());
    joined.push_back(k);
  };
  if (from < 0) {
    add(j);
  } else if (from != into) {
    std::vector<int>& others = members_[static_cast<std::size_t>(from)];
    for (const int k : others) add(k);
    others.clear();
    unused_.push_back(from);
  }
  joined_spheres_ += static_cast<std::int64_t>(joined.size());
  return joined;
}

void RigidClusters::remove(int i) {
  ++departures_;
  const int c = cluster_[i];
  std::vector<int>& members = members_[static_cast<std::size_t>(c)];
  const int last = members.back();
  members[static_cast<std::size_t>(place_[i])] = last;
  place_[last] = place_[i];
  members.pop_back();
  cluster_[i] = -1;
  if (members.size() == 1) {
    cluster_[members.front()] = -1;
    members.clear();
    unused_.push_back(c);
  }
}

EngineStatistics RigidClusters::named() const {
  return {{"cluster_joins", joins_}, {"cluster_joined_spheres", joined_spheres_}, {"cluster_departures", departures_}};
}

}  // namespace pdamp::hard
