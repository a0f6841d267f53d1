// SPDX-License-Identifier: Apache-2.0
// Reads tests/data/bruneton2017_sky_subset.csv: comment lines start with '#',
// then a header row naming the columns, then one row per geometry.
#pragma once

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/base/math.hpp"

namespace welkin::test {

// The peer's wavelengths (Bruneton 2017's demo, 680/550/440 nm), which tests compare at
// per channel; the library's default is four others (atmosphere.hpp).
inline const std::vector<double> kPeerWavelengthsNm{680.0, 550.0, 440.0};

struct PeerRow {
    std::map<std::string, double> v;
    double operator[](const std::string& column) const { return v.at(column); }

    // Geometry of the row in Welkin's frame: sun in the XZ plane at azimuth 0, view at
    // azimuth rel_azimuth_deg (counter-clockwise from +X).
    glm::dvec3 sun_direction() const {
        const double z = v.at("sun_zenith_deg") * kDegree;
        return {std::sin(z), 0.0, std::cos(z)};
    }
    glm::dvec3 view_direction() const {
        const double z = v.at("view_zenith_deg") * kDegree, a = v.at("rel_azimuth_deg") * kDegree;
        return {std::sin(z) * std::cos(a), std::sin(z) * std::sin(a), std::cos(z)};
    }
};

inline std::vector<PeerRow> read_peer_table() {
    const std::string path = std::string(WELKIN_TEST_DATA_DIR) + "/bruneton2017_sky_subset.csv";
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot open the peer table " + path);
    std::vector<std::string> names;
    std::vector<PeerRow> rows;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::vector<std::string> cells;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
        if (names.empty()) {
            names = cells;
            continue;
        }
        PeerRow row;
        for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i)
            row.v[names[i]] = std::stod(cells[i]);
        rows.push_back(std::move(row));
    }
    return rows;
}

// Median and maximum of a list of values.
inline std::pair<double, double> median_and_max(std::vector<double> x) {
    if (x.empty()) return {0.0, 0.0};
    std::sort(x.begin(), x.end());
    return {x[x.size() / 2], x.back()};
}

}  // namespace welkin::test
