// SPDX-License-Identifier: Apache-2.0
// The union of cloud density sources; see clouds/union.hpp.
#include "welkin/clouds/union.hpp"

#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {

CloudUnion::CloudUnion(std::vector<std::shared_ptr<const CloudDensity>> sources)
    : sources_(std::move(sources)) {
    if (sources_.empty() || sources_.size() > kMaxSources)
        throw InvalidArgument("sources",
                              fmt::format("a cloud union needs between 1 and {} density sources, got {}",
                                          kMaxSources, sources_.size()));
    feature_size_ = std::numeric_limits<double>::infinity();
    for (const auto& s : sources_) {
        if (!s) throw InvalidArgument("sources", "a cloud density source is null");
        feature_size_ = std::min(feature_size_, s->feature_size_m());
    }
}

double CloudUnion::sigma_t(const glm::dvec3& p) const {
    double sum = 0.0;
    for (const auto& s : sources_) sum += s->sigma_t(p);
    return sum;
}

void CloudUnion::segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const {
    if (sources_.size() == 1) {
        sources_.front()->segments(ray, t_max, out);
        return;
    }
    thread_local std::vector<std::vector<MajorantSegment>> lists;
    if (lists.size() < sources_.size()) lists.resize(sources_.size());
    for (std::size_t k = 0; k < sources_.size(); ++k) sources_[k]->segments(ray, t_max, lists[k]);
    // Only this union's lists: the thread_local may be longer (a larger union ran here).
    merge_majorant_segments(std::span<const std::vector<MajorantSegment>>(lists.data(), sources_.size()),
                            out);
}

void merge_majorant_segments(std::span<const std::vector<MajorantSegment>> lists,
                             std::vector<MajorantSegment>& out) {
    out.clear();
    const std::size_t K = lists.size();
    // Per list: the index of its current segment and whether the sweep is inside it.
    thread_local std::vector<std::size_t> next;
    thread_local std::vector<char> open;
    next.assign(K, 0);
    open.assign(K, 0);
    const auto skip_empty = [&](std::size_t k) {
        while (next[k] < lists[k].size() && !(lists[k][next[k]].t1 > lists[k][next[k]].t0)) ++next[k];
    };
    for (std::size_t k = 0; k < K; ++k) skip_empty(k);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    double t = -kInf;
    for (;;) {
        // The next end point: the start of a closed list's next segment or the end of an open one.
        double t_next = kInf;
        for (std::size_t k = 0; k < K; ++k) {
            if (next[k] >= lists[k].size()) continue;
            const MajorantSegment& s = lists[k][next[k]];
            t_next = std::min(t_next, open[k] ? s.t1 : s.t0);
        }
        if (t_next == kInf) break;
        // The piece [t, t_next] under the lists open now.
        double majorant = 0.0;
        bool any = false;
        for (std::size_t k = 0; k < K; ++k)
            if (open[k]) {
                majorant += lists[k][next[k]].majorant;
                any = true;
            }
        if (any && t_next > t) out.push_back({t, t_next, majorant});
        t = std::max(t, t_next);
        // Open and close what changes at t (a segment ending where the next begins: both).
        for (std::size_t k = 0; k < K; ++k) {
            for (;;) {
                if (next[k] >= lists[k].size()) break;
                const MajorantSegment& s = lists[k][next[k]];
                if (open[k] && s.t1 <= t) {
                    open[k] = 0;
                    ++next[k];
                    skip_empty(k);
                } else if (!open[k] && s.t0 <= t) {
                    open[k] = 1;
                } else {
                    break;
                }
            }
        }
    }
}

}  // namespace welkin
