#include "common/scene/deform_lod.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vistel {

Status validateDeformLodSettings(const DeformLodSettings& s) {
  if (!std::isfinite(s.full_radius_m) || s.full_radius_m < 0.0f) {
    return fail("full_radius_m must be finite and >= 0 (got {})", s.full_radius_m);
  }
  if (!std::isfinite(s.reduced_radius_m) || s.reduced_radius_m < s.full_radius_m) {
    return fail("reduced_radius_m must be finite and >= full_radius_m (got {})",
                s.reduced_radius_m);
  }
  if (!std::isfinite(s.hysteresis_m) || s.hysteresis_m < 0.0f) {
    return fail("hysteresis_m must be finite and >= 0 (got {})", s.hysteresis_m);
  }
  if (s.reduced_every < 1 || s.reduced_every > 60) {
    return fail("reduced_every must be in 1..60 (got {})", s.reduced_every);
  }
  if (s.max_full < 0) return fail("max_full must be >= 0 (got {})", s.max_full);
  if (s.max_reduced < 0) return fail("max_reduced must be >= 0 (got {})", s.max_reduced);
  return {};
}

void chooseDeformTiers(const DeformLodSettings& settings, const DeformLodInput& input,
                       DeformLodScratch& scratch, std::span<DeformTier> out) {
  const std::size_t n = input.positions.size();
  if (out.size() != n) return;
  if (!settings.enabled) {
    std::fill(out.begin(), out.end(), DeformTier::kFull);
    return;
  }
  const bool have_contact = input.in_contact.size() == n;
  const bool have_previous = input.previous.size() == n;
  auto contact = [&](std::size_t i) {
    return settings.contact_full && have_contact && input.in_contact[i] != 0;
  };

  // Floor-plane distances and the tier each body wants on distance (with hysteresis) and
  // contact alone.
  scratch.distance.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec2 d(input.positions[i].x - input.viewer.x, input.positions[i].z - input.viewer.z);
    const float dist = std::sqrt(d.x * d.x + d.y * d.y);
    scratch.distance[i] = std::isfinite(dist) ? dist : std::numeric_limits<float>::infinity();
    const DeformTier before = have_previous ? input.previous[i] : DeformTier::kRigid;
    const float full_r =
        settings.full_radius_m + (before == DeformTier::kFull ? settings.hysteresis_m : 0.0f);
    const float reduced_r =
        settings.reduced_radius_m + (before != DeformTier::kRigid ? settings.hysteresis_m : 0.0f);
    const float di = scratch.distance[i];
    out[i] = contact(i) || di <= full_r ? DeformTier::kFull
             : di <= reduced_r          ? DeformTier::kReduced
                                        : DeformTier::kRigid;
  }

  // Priority: bodies in contact first, then the nearest, then the lower index.
  scratch.order.resize(n);
  for (std::size_t i = 0; i < n; ++i) scratch.order[i] = static_cast<int>(i);
  std::sort(scratch.order.begin(), scratch.order.end(), [&](int a, int b) {
    const auto ua = static_cast<std::size_t>(a);
    const auto ub = static_cast<std::size_t>(b);
    if (contact(ua) != contact(ub)) return contact(ua);
    if (scratch.distance[ua] != scratch.distance[ub]) {
      return scratch.distance[ua] < scratch.distance[ub];
    }
    return a < b;
  });

  // Budgets, in priority order: the full-rate one, then the lower-rate one (which the
  // bodies dropped from full rate join).
  int full = 0;
  int reduced = 0;
  for (const int body : scratch.order) {
    DeformTier& tier = out[static_cast<std::size_t>(body)];
    if (tier == DeformTier::kFull && full++ >= settings.max_full) tier = DeformTier::kReduced;
    if (tier == DeformTier::kReduced && reduced++ >= settings.max_reduced) {
      tier = DeformTier::kRigid;
    }
  }
}

bool deformsOnFrame(DeformTier tier, int body, std::int64_t frame, int reduced_every) {
  switch (tier) {
    case DeformTier::kFull:
      return true;
    case DeformTier::kReduced: {
      const std::int64_t k = std::max(reduced_every, 1);
      const std::int64_t phase = (frame + body) % k;
      return phase == 0;
    }
    case DeformTier::kRigid:
      return false;
  }
  return false;
}

DeformTierCounts countTiers(std::span<const DeformTier> tiers) {
  DeformTierCounts c;
  for (const DeformTier t : tiers) {
    if (t == DeformTier::kFull) ++c.full;
    if (t == DeformTier::kReduced) ++c.reduced;
    if (t == DeformTier::kRigid) ++c.rigid;
  }
  return c;
}

}  // namespace vistel
