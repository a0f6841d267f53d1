# SPDX-License-Identifier: Apache-2.0
"""The independent ephemeris for tests/python/test_place_and_time.py: JPL's DE421 through
Skyfield, run in build/venv-ephemeris (scripts/install_ephemeris_venv.sh), never in the
Python that imports welkin.

Reads a JSON list of cases on stdin, each {"scale": "utc" | "ut1", "time": [Y, M, D, h, m,
s], "latitude_deg", "longitude_deg", "height_m", "pressure_hpa", "temperature_c"}, and
prints a JSON list: per case the sun's and the moon's apparent topocentric elevation
(refracted with Skyfield's Bennett formula, and airless) and azimuth (clockwise from
north), and the moon's topocentric phase angle (the angle at the moon between the sun and
the observer) and illuminated fraction. Reads only the files skyfield-data installed.
"""

import json
import sys
import warnings

import numpy as np
from skyfield.api import Loader, wgs84
from skyfield_data import get_skyfield_data_path

# skyfield-data's IERS table (finals2000A.all) carries an expiry date; the builtin
# timescale used here does not read it.
warnings.filterwarnings("ignore", category=RuntimeWarning, module="skyfield_data")


def main() -> None:
    load = Loader(get_skyfield_data_path(), expire=False)
    ts = load.timescale(builtin=True)
    eph = load("de421.bsp")
    earth, sun, moon = eph["earth"], eph["sun"], eph["moon"]
    out = []
    for case in json.load(sys.stdin):
        t = (ts.utc if case["scale"] == "utc" else ts.ut1)(*case["time"])
        observer = earth + wgs84.latlon(
            case["latitude_deg"], case["longitude_deg"], elevation_m=case["height_m"]
        )
        here = observer.at(t)
        result = {}
        vectors = {}
        for name, body in (("sun", sun), ("moon", moon)):
            apparent = here.observe(body).apparent()
            alt, az, _ = apparent.altaz(
                temperature_C=case["temperature_c"], pressure_mbar=case["pressure_hpa"]
            )
            alt0, _, _ = apparent.altaz()
            result[name] = {
                "elevation_deg": alt.degrees,
                "airless_elevation_deg": alt0.degrees,
                "azimuth_deg": az.degrees,
            }
            vectors[name] = (body - observer).at(t).position.au  # geometric, ICRS
        to_sun = vectors["sun"] - vectors["moon"]
        to_observer = -vectors["moon"]
        c = float(np.dot(to_sun, to_observer) / np.linalg.norm(to_sun) / np.linalg.norm(to_observer))
        result["moon"]["phase_angle_deg"] = float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
        result["moon"]["illuminated_fraction"] = 0.5 * (1.0 + c)
        out.append(result)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
