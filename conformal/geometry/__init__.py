"""Wheel-rail geometry: from profiles to contact patches (the seed's geometry and kinematic stages).

profiles   reading and checking profile files (CSV, CONTACT .prw/.prr), built-in names
spline     smoothing spline by arc length, C2 (seed Eq. 55 needs curvatures), smoothing error
surfaces   the rail as an extrusion, the wheel as a surface of revolution (seed Eqs. 50-53)
placement  track (gauge, cant) and wheelset (shift, yaw, roll, flange-back spacing) placement
search     global search of all gap minima + Newton-Raphson refinement (seed Eqs. 54-56)
patches    interpenetration regions, reference points, planar and curved grids from true profiles
kinematics creepages from wheelset velocities (seed Eqs. 58-61)
wheelrail  scene -> contact problems, vertical load balance, combined result (track-frame forces)
sweep      rolling-radius difference, contact angles and positions versus lateral shift
"""
