#pragma once
// A building revisited after its furniture was moved: what a localization in yesterday's map meets.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

/// Moves each piece of furniture (a box standing on the ground floor, 0.3-2.1 m tall, 0.3-1.6 m a
/// side) 0.4-1.0 m in a direction drawn from the seed, where it stays inside the scene, off the
/// walls and pillars (boxes taller than 2.5 m) and 0.7 m from the rig's route (x, y samples);
/// a piece with no such place in eight draws stays. Returns how many moved.
std::size_t rearrangeFurniture(std::vector<Box>* boxes, const std::vector<Eigen::Vector2d>& route, std::uint64_t seed);

}  // namespace mmlio::sim
