# SPDX-License-Identifier: Apache-2.0
"""The independent reference for tests/python/test_night_sky.py's star positions: Skyfield
(with JPL's DE421 for the Earth's motion), run in build/venv-ephemeris
(scripts/install_ephemeris_venv.sh), never in the Python that imports welkin.

Reads a JSON list of cases on stdin, each {"time": [Y, M, D, h, m, s] (UTC),
"latitude_deg", "longitude_deg", "height_m", "pressure_hpa", "temperature_c", "ra_deg",
"dec_deg", "pm_ra_mas_yr", "pm_dec_mas_yr"} (Hipparcos, epoch J1991.25), and prints a
JSON list of the star's apparent elevation (refracted with Skyfield's Bennett formula) and
azimuth (clockwise from north).
"""

import json
import sys
import warnings

from skyfield.api import Loader, Star, wgs84
from skyfield_data import get_skyfield_data_path

warnings.filterwarnings("ignore", category=RuntimeWarning, module="skyfield_data")

J1991_25 = 2448349.0625  # TT


def main() -> None:
    load = Loader(get_skyfield_data_path(), expire=False)
    ts = load.timescale(builtin=True)
    earth = load("de421.bsp")["earth"]
    out = []
    for case in json.load(sys.stdin):
        t = ts.utc(*case["time"])
        star = Star(
            ra_hours=case["ra_deg"] / 15.0,
            dec_degrees=case["dec_deg"],
            ra_mas_per_year=case["pm_ra_mas_yr"],
            dec_mas_per_year=case["pm_dec_mas_yr"],
            epoch=J1991_25,
        )
        place = earth + wgs84.latlon(
            case["latitude_deg"], case["longitude_deg"], elevation_m=case["height_m"]
        )
        alt, az, _ = (
            place.at(t)
            .observe(star)
            .apparent()
            .altaz(temperature_C=case["temperature_c"], pressure_mbar=case["pressure_hpa"])
        )
        out.append({"elevation_deg": alt.degrees, "azimuth_deg": az.degrees})
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
