#!/usr/bin/env python3
"""Writes data/rom/synthetic_liftoff.csv: a SYNTHETIC damper table (not a characterisation) for
the reduced-order model's tests, benchmark and plot check. A bed of mass m_p that moves with its
container below Gamma = 1 and lifts off above it, with the trends of docs/rom.md:

    m_app = m_p                          for Gamma <= 1,  m_p Gamma^-2 above
    c_eq  = kappa m_p omega (1 - 1/Gamma) for Gamma > 1,   0 below
    spreads: 0.02 m_p and 0.05 c_eq where the bed is lifted, 0 below; the point at the largest
    amplitude and frequency (Gamma = 63) is marked unsettled.

On 8 amplitudes from 0.1 to 20 mm (geometric) and 10 frequencies from 10 to 28 Hz.

usage: tools/rom_synthetic_table.py [OUT.csv]   (default data/rom/synthetic_liftoff.csv)
"""
import math
import os
import sys

BED_MASS_KG = 0.008
GRAVITY_M_S2 = 9.81
KAPPA = 0.1
AMPLITUDES_M = [1e-4 * 200 ** (i / 7) for i in range(8)]
FREQUENCIES_HZ = [10.0 + 2 * j for j in range(10)]


def point(amplitude_m, frequency_hz):
    omega = 2 * math.pi * frequency_hz
    gamma = amplitude_m * omega * omega / GRAVITY_M_S2
    if gamma <= 1:
        return gamma, BED_MASS_KG, 0.0, 0.0, 0.0
    c_eq = KAPPA * BED_MASS_KG * omega * (1 - 1 / gamma)
    return gamma, BED_MASS_KG / gamma**2, c_eq, 0.02 * BED_MASS_KG, 0.05 * c_eq


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "data", "rom", "synthetic_liftoff.csv")
    lines = [
        "# format = pdamp damper table 1",
        "# source = synthetic lift-off table (tools/rom_synthetic_table.py), not a characterisation",
        f"# bed_mass_kg = {BED_MASS_KG!r}",
        f"# gravity_m_s2 = {GRAVITY_M_S2!r}",
        f"# m_app = m_p min(1, Gamma^-2); c_eq = {KAPPA} m_p omega max(0, 1 - 1/Gamma); see the script",
        "amplitude_m,frequency_hz,gamma,m_app_kg,c_eq_N_s_m,m_app_spread_kg,c_eq_spread_N_s_m,settled",
    ]
    for f in FREQUENCIES_HZ:
        for a in AMPLITUDES_M:
            gamma, m_app, c_eq, m_spread, c_spread = point(a, f)
            settled = 0 if (a, f) == (AMPLITUDES_M[-1], FREQUENCIES_HZ[-1]) else 1
            lines.append(",".join(repr(v) for v in (a, f, gamma, m_app, c_eq, m_spread, c_spread)) + f",{settled}")
    with open(out, "w") as file:
        file.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
