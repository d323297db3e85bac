#!/usr/bin/env python3
"""Normal coefficient of restitution of a head-on collision (no gravity) for
 paper law     : Fn = kn d^1.5 + cn d'                   (constant dashpot)
 LIGGGHTS law  : Fn = kn d^1.5 + cn*sqrt(d/dref) d'      (hertz/stiffness as parameterised in params.in)
each (i) 'exact' (RK4, h=1e-9 s) and (ii) with LAMMPS/LIGGGHTS velocity-Verlet at dt=2.5e-6 s
(force evaluated with the half-step velocity), which is what the DEM run actually does.
Particle-wall: M* = m; particle-particle: M* = m/2.  v_rel = relative normal impact speed.
No force limiting (limitForce off): the contact ends when the overlap returns to 0."""
import math
rho, dp, kn, cn, dref, DT = 9000.0, 0.88e-3, 3.6e5, 0.01, 1e-5, 2.5e-6
m = rho*math.pi/6*dp**3

def force(d, v, ligg):
    if d <= 0: return 0.0
    c = cn*math.sqrt(d/dref) if ligg else cn
    return -(kn*d**1.5 + c*v)

def e_exact(v0, M, ligg, h=1e-9):
    d, v = 0.0, v0
    a = lambda d, v: force(d, v, ligg)/M if d > 0 else -cn*v/M*(0 if not ligg else 0)
    while True:
        k1d, k1v = v, a(d, v)
        k2d, k2v = v+0.5*h*k1v, a(d+0.5*h*k1d, v+0.5*h*k1v)
        k3d, k3v = v+0.5*h*k2v, a(d+0.5*h*k2d, v+0.5*h*k2v)
        k4d, k4v = v+h*k3v, a(d+h*k3d, v+h*k3v)
        d += h*(k1d+2*k2d+2*k3d+k4d)/6; v += h*(k1v+2*k2v+2*k3v+k4v)/6
        if d < 0: return -v/v0

def e_vv(v0, M, ligg, dt=DT, gap=2e-6):
    d, v, f = -gap, v0, 0.0
    while True:
        v += 0.5*dt*f/M; d += dt*v
        f = force(d, v, ligg)
        v += 0.5*dt*f/M
        if d < -gap and v < 0: return -v/v0

if __name__ == "__main__":
    print("contact  v_rel[m/s]  paper(exact)  paper(VV,dt=2.5us)  LIGGGHTS-law(exact)  LIGGGHTS-law(VV,dt=2.5us)")
    for name, M, vs in (("p-wall", m, (0.01, 0.1, 0.3, 1.0, 2.0)), ("p-p", m/2, (0.02, 0.2, 0.6, 2.0, 4.0))):
        for v0 in vs:
            print(f"{name:7s}  {v0:9.2f}   {e_exact(v0,M,False):.4f}        {e_vv(v0,M,False):.4f}              "
                  f"{e_exact(v0,M,True):.4f}               {e_vv(v0,M,True):.4f}")
