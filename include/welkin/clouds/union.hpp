// SPDX-License-Identifier: Apache-2.0
// Several cloud density sources as one: the union of a scene's layers and volumes.
//
// Extinction is additive: where media overlap, a photon meets the particles of each, and
// the probability of passing a length dt is the product of the transmittances,
// exp(-sigma_1 dt) exp(-sigma_2 dt) = exp(-(sigma_1 + sigma_2) dt). So
//     sigma_t(p) = sum_k sigma_t,k(p),
// with one albedo and phase for all (cloud droplets everywhere: clouds/lighting.hpp).
//
// Majorant segments. Each source's segments of the ray are merged by a sweep over their
// end points: between two consecutive end points the set of open segments does not change,
// and the bound there is the sum of their majorants (sum of bounds bounds the sum). Pieces
// where no segment is open are left out (sigma_t is zero there). Adjacent pieces with the
// same set of open segments cannot occur (an end point separates them), so the output has
// at most 2 (number of input segments) - 1 pieces, increasing in t, not overlapping, and
// covers every input segment. One source is passed through unchanged.
//
// feature_size_m: the smallest of the sources' (the finest structure must be resolved).
//
// Thread safety: immutable; segments() uses per-thread scratch space.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "welkin/clouds/density.hpp"

namespace welkin {

class CloudUnion final : public CloudDensity {
public:
    // The most sources a union may have (docs/limits.md): each is visited at every step.
    static constexpr std::size_t kMaxSources = 96;
    // At least one source and at most kMaxSources, none null (InvalidArgument naming
    // "sources" otherwise).
    explicit CloudUnion(std::vector<std::shared_ptr<const CloudDensity>> sources);

    double sigma_t(const glm::dvec3& p) const override;
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override;
    double feature_size_m() const override { return feature_size_; }

    std::size_t size() const { return sources_.size(); }

private:
    std::vector<std::shared_ptr<const CloudDensity>> sources_;
    double feature_size_;
};

// Merges segment lists (each increasing and non-overlapping) into one as described above.
void merge_majorant_segments(std::span<const std::vector<MajorantSegment>> lists,
                             std::vector<MajorantSegment>& out);

}  // namespace welkin
