// SPDX-License-Identifier: Apache-2.0
// Shared by the cloud tests: a homogeneous box of cloud (closed forms), an airless
// atmosphere, and small VDB files written with OpenVDB into a temporary folder.
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/clouds/density.hpp"

namespace welkin::test {

// The bruneton2017 sun over no air at all: the sun's light reaches a cloud unchanged, there
// is no sky light, no air in front of the cloud and no aerial perspective.
inline Atmosphere airless() {
    Atmosphere a = Atmosphere::preset("bruneton2017");
    const std::size_t n = a.channels();
    a.rayleigh_scattering.assign(n, 0.0);
    a.mie_scattering.assign(n, 0.0);
    a.mie_extinction.assign(n, 0.0);
    a.absorption_extinction.assign(n, 0.0);
    a.ground_albedo.assign(n, 0.0);
    return a;
}

// A W x H grid of directions over the upper sky, elevations 3 to 87 degrees, row 0 at the
// top: an equirect sky's upper half (the upsampled grids' tests).
inline std::vector<glm::dvec3> sky_grid(int W, int H) {
    std::vector<glm::dvec3> d;
    for (int j = 0; j < H; ++j) {
        const double el = (87.0 - 84.0 * j / (H - 1)) * std::numbers::pi / 180.0;
        for (int i = 0; i < W; ++i) {
            const double az = 2.0 * std::numbers::pi * (i + 0.5) / W;
            d.push_back({std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)});
        }
    }
    return d;
}

// sigma_t constant inside [lo, hi], zero outside.
class HomogeneousBox final : public CloudDensity {
public:
    HomogeneousBox(glm::dvec3 lo, glm::dvec3 hi, double sigma_t) : lo_(lo), hi_(hi), sigma_(sigma_t) {}
    double sigma_t(const glm::dvec3& p) const override {
        for (int a = 0; a < 3; ++a)
            if (p[a] < lo_[a] || p[a] > hi_[a]) return 0.0;
        return sigma_;
    }
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override {
        out.clear();
        double t0 = 0.0, t1 = t_max;
        if (clip_ray_to_box(ray, lo_, hi_, t0, t1) && t1 > t0) out.push_back({t0, t1, sigma_});
    }
    double feature_size_m() const override { return 1e-3; }

private:
    glm::dvec3 lo_, hi_;
    double sigma_;
};

// A folder under the system temp directory, removed with its files at the end.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        path = std::filesystem::temp_directory_path() /
               ("welkin_clouds_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
    static int& counter() {
        static int c = 0;
        return c;
    }
};

// Writes grids to a .vdb file.
inline void write_vdb(const std::string& path, const openvdb::GridPtrVec& grids) {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.write(grids);
    file.close();
}

// A fog-volume FloatGrid named `name`, voxel size `voxel_m`, filled by value(i, j, k) on
// the cube [-n, n]^3 (zeros are left inactive).
inline openvdb::FloatGrid::Ptr make_float_grid(const std::string& name, double voxel_m, int n,
                                               const std::function<float(int, int, int)>& value) {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(name);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_m));
    auto acc = grid->getAccessor();
    for (int k = -n; k <= n; ++k)
        for (int j = -n; j <= n; ++j)
            for (int i = -n; i <= n; ++i) {
                const float v = value(i, j, k);
                if (v != 0.0f) acc.setValue(openvdb::Coord(i, j, k), v);
            }
    return grid;
}

}  // namespace welkin::test
