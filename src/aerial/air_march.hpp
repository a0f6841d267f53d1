// SPDX-License-Identifier: Apache-2.0
// The march both ways of aerial perspective share (internal to the aerial library): the
// per-pixel passes and the froxel volume (aerial_perspective.cpp) and the direction and
// screen tables (aerial_table.cpp) all integrate the air along a ray with march_segment
// and turn the spectral result into the passes' RGB with PassColour. The integral and its
// sources are derived in aerial_perspective.cpp's opening comment.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/batch.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/base/camera.hpp"
#include "welkin/base/progress.hpp"
#include "welkin/color/color_space.hpp"

namespace welkin::aerial_march {

// Largest optical depth kept in the volume (T = e^-80 ~ 2e-35, below any float image).
constexpr float kMaxOpticalDepth = 80.0f;

// One ray in planet-centred coordinates with its phase values (nu is constant along it).
struct AirRay {
    glm::dvec3 p0;   // origin relative to the planet centre, m
    glm::dvec3 d;    // unit direction
    glm::dvec3 sun;  // unit, towards the sun
};

// The camera ray `ray` of `view` in planet-centred coordinates, with the sun's direction.
AirRay air_ray(const AerialView& view, const CameraRays::Ray& ray, const glm::dvec3& sun);

// Adds [t0, t1] of the ray in n steps to (L, T) of one batch; L per unit sun irradiance.
void march_segment(const AtmosphereLuts::Batch& b, const AirRay& ray, float rayleigh_p, float mie_p,
                   double t0, double t1, int n, Spectrum4& L, Spectrum4& T);

// Spectral (L, T) of all channels -> the passes' RGB (see aerial_perspective.hpp): the
// sky's conversion for L, the sunlit-surface ratio for T,
//     L3 = exposure M_sky L,    T3 = clamp01(M_sun (E_sun T) / white),  white = M_sun E_sun
// (white: the sun's own colour, so that air that dims every wavelength alike leaves a
// sunlit surface's colour as it is). Both are linear in the spectrum: one 3 x C matrix
// each, built once.
class PassColour {
public:
    PassColour(const Atmosphere& atm, double exposure, ColorSpace space);

    std::size_t channels() const { return channels_; }

    // L and T hold channels() floats each.
    void convert(const float* L, const float* T, float* L3, float* T3) const;

private:
    std::size_t channels_;
    std::array<double, 3> luminance_{};
    std::vector<double> sky_, sun_;  // 3 x C, row-major
};

// One ray marched once through increasing distances 0 < t_1 < ... < t_n: the passes' RGB
// (in-scattering times the exposure, transmittance) at each. The buffers are per thread.
class SliceMarcher {
public:
    SliceMarcher(const AtmosphereLuts& luts, const PassColour& colour, int steps)
        : luts_(luts), colour_(colour), steps_(steps) {}

    // L3 and T3 receive 3 floats per distance.
    void march(const AirRay& ray, std::span<const double> distances, float* L3, float* T3);

private:
    const AtmosphereLuts& luts_;
    const PassColour& colour_;
    int steps_;
    std::vector<float> L_, T_;
};

// -ln T, at most kMaxOpticalDepth.
float optical_depth_of(float T);

// Marches one ray per point (i, j) of a columns x rows grid through its slices, in
// parallel, one SliceMarcher per thread: ray(i, j, distances) gives the point's ray and may
// set its slice distances (else they stay `distances`); store(i, j, L, T) receives the
// passes, 3 floats per slice each. Progress counts grid points.
template <class RayOf, class Store>
void march_grid(const AtmosphereLuts& luts, const PassColour& colour, int steps, int columns, int rows,
                const std::vector<double>& distances, Progress* progress, RayOf ray, Store store) {
    ProgressTracker tracker(progress, std::size_t(columns) * std::size_t(rows));
    tbb::parallel_for(tbb::blocked_range<int>(0, columns * rows), [&](const tbb::blocked_range<int>& range) {
        SliceMarcher marcher(luts, colour, steps);
        std::vector<double> d = distances;
        std::vector<float> L(d.size() * 3), T(L.size());
        for (int point = range.begin(); point != range.end(); ++point) {
            const int i = point % columns, j = point / columns;
            const AirRay r = ray(i, j, d);
            marcher.march(r, d, L.data(), T.data());
            store(i, j, L, T);
            tracker.advance();
        }
    });
    tracker.finish();
}

}  // namespace welkin::aerial_march
