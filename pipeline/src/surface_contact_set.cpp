// SurfaceContact::set_collider (surface_contact.hpp): a collider replaced between steps.
#include <mbi/error.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <algorithm>
#include <string>

namespace mbi::pipeline {

void SurfaceContact::set_collider(size_t i, const Collider& collider) {
  if (i >= colliders_.size())
    throw Error("contact: collider " + std::to_string(i) + " out of range (" + std::to_string(colliders_.size()) +
                " colliders)");
  check_collider(collider, "collider " + std::to_string(i));
  colliders_[i] = collider;
  lipschitz_[i] = distance_lipschitz(collider);
  steepest_ = *std::max_element(lipschitz_.begin(), lipschitz_.end());
  set_time(time_);  // poses it and forgets what was evaluated with the old one
}

}  // namespace mbi::pipeline
