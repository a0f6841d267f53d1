// SPDX-License-Identifier: Apache-2.0
// What lights a cloud: the sun's irradiance at a point, after the atmosphere, and the
// isotropic sky radiance around it. Both cloud integrators (the fast march and the path
// tracer) use the same illumination, so the reference tests the lighting approximation
// alone, not a different light.
//
// From the atmosphere (AtmosphereIllumination), at a point p at radius r = |p - centre|
// with the sun at zenith cosine mu_s there, per channel:
//   sun:  E_sun T(r, mu_s) times the visible fraction of the disc (TransmittanceLut::to_sun,
//         Bruneton 2017's GetTransmittanceToSun): the sun's colour at the cloud's altitude;
//   sky:  E_sun Psi_ms(r, mu_s), the multiple-scattering LUT's a_0 (multiscattering_lut.hpp):
//         the mean over the sphere of the sky radiance arriving at p (all orders of air
//         scattering and the ground's reflection), in Hillaire 2020's model. A cloud lit
//         by it is lit as by a uniform sky of that radiance (the sky's azimuthal and
//         zenith structure is left out, as in Hillaire 2016's cloud ambient term).
// Units: W m^-2 nm^-1 (irradiance, normal incidence) and W m^-2 sr^-1 nm^-1.
// The air between the cloud and the camera (aerial perspective) is not part of this.
#pragma once

#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/observer.hpp"

namespace welkin {

class CloudIllumination {
public:
    virtual ~CloudIllumination() = default;
    virtual std::size_t channels() const = 0;
    virtual glm::dvec3 sun_direction() const = 0;                            // unit, towards the sun
    virtual glm::dvec3 zenith(const glm::dvec3& p) const = 0;                // unit, the local vertical at p
    virtual void sun_irradiance(const glm::dvec3& p, float* out) const = 0;  // channels() values
    virtual void ambient_radiance(const glm::dvec3& p, float* out) const = 0;  // channels() values
};

// The same light everywhere (tests, and scenes lit without an atmosphere).
class ConstantIllumination final : public CloudIllumination {
public:
    // sun_direction normalised here; InvalidArgument if it is not a finite non-zero vector
    // or the two spectra differ in length / hold negative or non-finite values.
    ConstantIllumination(const glm::dvec3& sun_direction, std::vector<float> sun_irradiance,
                         std::vector<float> ambient_radiance);
    std::size_t channels() const override { return sun_.size(); }
    glm::dvec3 sun_direction() const override { return s_; }
    glm::dvec3 zenith(const glm::dvec3&) const override { return {0.0, 0.0, 1.0}; }
    void sun_irradiance(const glm::dvec3&, float* out) const override;
    void ambient_radiance(const glm::dvec3&, float* out) const override;

private:
    glm::dvec3 s_;
    std::vector<float> sun_, ambient_;
};

// Sun and sky from the atmosphere's LUTs; the world origin stands observer.altitude_m above
// the ground (the planet centre straight below it).
class AtmosphereIllumination final : public CloudIllumination {
public:
    AtmosphereIllumination(const Atmosphere& atmosphere, const Observer& observer,
                           const LutResolution& resolution = {});
    std::size_t channels() const override { return luts_->channels(); }
    glm::dvec3 sun_direction() const override { return s_; }
    glm::dvec3 zenith(const glm::dvec3& p) const override;
    void sun_irradiance(const glm::dvec3& p, float* out) const override;
    void ambient_radiance(const glm::dvec3& p, float* out) const override;
    // Its atmosphere's LUTs (for the air in front of the clouds, aerial_along_rays).
    const AtmosphereLuts& luts() const { return *luts_; }

private:
    std::shared_ptr<const AtmosphereLuts> luts_;
    glm::dvec3 s_, centre_;
};

}  // namespace welkin
