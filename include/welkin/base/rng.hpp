// SPDX-License-Identifier: Apache-2.0
// Random numbers for the reference path tracer: a counter-based stream, and randomised
// quasi-Monte Carlo points for the first dimensions of each path.
//
// Every path draws from its own stream, keyed by (seed, direction index, path index), so
// its random numbers do not depend on which thread traces it or in which order: results
// are identical for any thread count. The key is hashed with the SplitMix64 finaliser
// (Steele, Lea & Flood 2014, "Fast splittable pseudorandom number generators", OOPSLA;
// the mixing constants are Stafford's "Mix13"), and the stream is SplitMix64 itself: a
// Weyl sequence of the key, each term passed through the same finaliser. SplitMix64
// passes BigCrush and is the generator Java's SplittableRandom uses; a path needs only a
// few dozen numbers, far below its period of 2^64.
#pragma once

#include <algorithm>
#include <cstdint>

namespace welkin {

// SplitMix64's output function: a bijective 64-bit mix with full avalanche.
inline constexpr std::uint64_t splitmix64_mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

class PathRng {
public:
    static constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;  // 2^64 / phi

    // The stream of path `path` of direction `direction` under `seed`; `stream` separates
    // independent uses of the same path index.
    PathRng(std::uint64_t seed, std::uint64_t direction, std::uint64_t path, std::uint64_t stream = 0)
        : state_(splitmix64_mix(splitmix64_mix(splitmix64_mix(splitmix64_mix(seed) + direction) + path) +
                                stream)) {}

    std::uint64_t next_u64() {
        state_ += kGolden;
        return splitmix64_mix(state_);
    }

    // Uniform in [0, 1): the top 53 bits.
    double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }

    // Uniform in (0, 1]: for logarithms.
    double uniform_open0() { return double((next_u64() >> 11) + 1) * 0x1.0p-53; }

private:
    std::uint64_t state_;
};

// Randomised quasi-Monte Carlo: the first kDimensions numbers of the paths of one batch
// come from a padded, Owen-scrambled Sobol' sequence; later ones from the path's PathRng.
//
// Dimensions go in pairs (0, 1), (2, 3), ...; each pair is the (0, 2)-sequence formed by
// the first two Sobol' dimensions (van der Corput, and the one whose generator matrix is
// Pascal's triangle mod 2), so n = 2^m paths stratify every pair's unit square into all
// elementary intervals of area 1/n. Pairs are decorrelated by shuffling the point index
// per pair ("padding", Kollig & Keller 2002), and every coordinate gets nested uniform
// (Owen) scrambling. Both use Burley 2020, "Practical Hash-based Owen Scrambling", JCGT
// 9(4): the Laine-Karras permutation applied to the bit-reversed value; its first step
// adds a random 32-bit seed, so each point is exactly uniform over the seeds, and a
// random fraction below 2^-32 fills the remaining mantissa bits. Each point is therefore
// uniformly distributed and the estimator stays unbiased; the batches are independent
// replicates (independent seeds), which is what the standard error is computed from.
class QmcSampler {
public:
    static constexpr int kDimensions = 24;

    static constexpr std::uint32_t reverse_bits(std::uint32_t x) {
        x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
        x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
        x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
        x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
        return (x >> 16) | (x << 16);
    }
    static constexpr std::uint32_t laine_karras(std::uint32_t x, std::uint32_t seed) {
        x += seed;
        x ^= x * 0x6c50b47cu;
        x ^= x * 0xb82f1e52u;
        x ^= x * 0xc7afe638u;
        x ^= x * 0x8d22f6e6u;
        return x;
    }
    static constexpr std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
        return reverse_bits(laine_karras(reverse_bits(x), seed));
    }
    // The second Sobol' dimension: generator columns v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1).
    static constexpr std::uint32_t sobol2(std::uint32_t index) {
        std::uint32_t x = 0, v = 0x80000000u;
        for (; index; index >>= 1, v ^= v >> 1)
            if (index & 1u) x ^= v;
        return x;
    }

    // Path `index` of a batch whose scrambling is keyed by `batch_key`; `rng` supplies the
    // low bits and the dimensions beyond kDimensions.
    QmcSampler(std::uint64_t batch_key, std::uint32_t index, PathRng& rng)
        : key_(batch_key), index_(index), rng_(rng) {}

    double next() {
        if (dim_ >= kDimensions) return rng_.uniform();
        const int pair = dim_ / 2, which = dim_ % 2;
        ++dim_;
        const std::uint64_t h = splitmix64_mix(key_ + std::uint64_t(pair) * PathRng::kGolden);
        const std::uint32_t shuffled = owen_scramble(index_, std::uint32_t(h));
        const std::uint32_t raw = which == 0 ? reverse_bits(shuffled) : sobol2(shuffled);
        const std::uint32_t x = owen_scramble(raw, std::uint32_t(h >> 32) ^ (which ? 0x9e3779b9u : 0u));
        return std::min((double(x) + rng_.uniform()) * 0x1.0p-32, 1.0 - 0x1.0p-53);
    }
    // Skips dimensions (keeps the pairs aligned with the path's events).
    void skip(int dims) { dim_ += dims; }

private:
    std::uint64_t key_;
    std::uint32_t index_;
    PathRng& rng_;
    int dim_ = 0;
};

}  // namespace welkin
