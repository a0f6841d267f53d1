// SPDX-License-Identifier: Apache-2.0
// A cache of the atmosphere's look-up tables (AtmosphereLuts), so that a sun change pays
// only for the sky-view LUT.
//
// The transmittance and multiple-scattering LUTs depend on the atmosphere and on their
// sizes alone (docs/design.md#data-flow); a host that moves the sun (the Blender add-on
// rotating a sun lamp, an animation) asks again and again for the same ones. get()
// returns the tables built for an exactly equal key (Atmosphere::operator== on every
// field, and the LutResolution) or builds them; a copy of the key is kept,
// never a hash, so two different atmospheres can never share tables. The tables a key
// yields do not depend on whether they came from the cache (building is deterministic),
// so cached and fresh results are identical.
//
// Thread-safety: get() may be called from any number of threads. The tables are
// immutable and handed out as shared_ptr, so an entry evicted while in use stays valid.
// The lock is not held while building (a build runs TBB tasks, and a thread waiting in
// them may run another task that calls get()); two threads missing on the same key at
// once may both build, and one result is kept.
#pragma once

#include <cstddef>
#include <list>
#include <memory>
#include <mutex>

#include "welkin/atmosphere/luts.hpp"

namespace welkin {

class AtmosphereLutCache {
public:
    // Keeps the `capacity` most recently used entries (at least 1).
    explicit AtmosphereLutCache(std::size_t capacity = 2);

    std::shared_ptr<const AtmosphereLuts> get(const Atmosphere& atmosphere, const LutResolution& resolution);

    void clear();
    // How many times get() has built tables (for tests and benchmarks).
    std::size_t builds() const;

    // The process-wide cache the lut method uses by default.
    static AtmosphereLutCache& shared();

private:
    struct Key {
        Atmosphere atmosphere;
        LutResolution resolution;
        bool operator==(const Key&) const = default;
    };
    static Key key_of(const Atmosphere& atmosphere, const LutResolution& resolution);

    struct Entry {
        Key key;
        std::shared_ptr<const AtmosphereLuts> luts;
    };
    mutable std::mutex mutex_;
    std::size_t capacity_;
    std::list<Entry> entries_;  // most recently used first
    std::size_t builds_ = 0;
};

}  // namespace welkin
