// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/lut_cache.hpp"

#include <algorithm>

namespace welkin {

AtmosphereLutCache::AtmosphereLutCache(std::size_t capacity)
    : capacity_(std::max<std::size_t>(capacity, 1)) {}

AtmosphereLutCache::Key AtmosphereLutCache::key_of(const Atmosphere& atmosphere,
                                                   const LutResolution& resolution) {
    return {atmosphere, resolution};
}

std::shared_ptr<const AtmosphereLuts> AtmosphereLutCache::get(const Atmosphere& atmosphere,
                                                              const LutResolution& resolution) {
    Key key = key_of(atmosphere, resolution);
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        const auto it =
            std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; });
        if (it != entries_.end()) {
            entries_.splice(entries_.begin(), entries_, it);  // most recently used first
            return entries_.front().luts;
        }
    }
    // Built outside the lock (see the header); validates the atmosphere and the options.
    auto luts = std::make_shared<const AtmosphereLuts>(atmosphere, resolution);
    const std::lock_guard<std::mutex> lock(mutex_);
    ++builds_;
    const auto it =
        std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; });
    if (it != entries_.end()) {
        entries_.splice(entries_.begin(), entries_, it);  // another thread built it meanwhile
        return entries_.front().luts;
    }
    entries_.push_front(Entry{std::move(key), luts});
    if (entries_.size() > capacity_) entries_.pop_back();
    return luts;
}

void AtmosphereLutCache::clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    entries_.clear();
}

std::size_t AtmosphereLutCache::builds() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return builds_;
}

AtmosphereLutCache& AtmosphereLutCache::shared() {
    static AtmosphereLutCache cache;
    return cache;
}

}  // namespace welkin
