# The peer comparison of issue 18: fluidsim (pseudo-spectral, RK4) on the Taylor-Green vortex
# at Re = 1600 to t = 5, for E(5) against the spectral DNS's 0.1184 and the wall time of the
# time stepping, to set beside `tumble run` of scenes/taylor-green-3d.ron at the same or
# another grid (same session, same machine).
#
#   python3 -m venv venv && venv/bin/pip install fluidsim fluidfft-fftw
#   OMP_NUM_THREADS=2 venv/bin/python docs/compare/fluidsim_taylor_green.py 64
#
# The last step is shortened to land on t = 5 exactly (fluidsim otherwise stops at the first
# step past t_end). Its `fft3d.with_fftw3d` transforms are sequential: it runs on one core.
# On two cores, under MPI (Debian's openmpi-bin and libopenmpi-dev, then
# `venv/bin/pip install mpi4py fluidfft-mpi_with_fftw`), with `fft3d.mpi_with_fftw1d`:
#
#   mpirun -np 2 venv/bin/python docs/compare/fluidsim_taylor_green.py 64
import sys, time, os
import numpy as np
from fluidsim.solvers.ns3d.solver import Simul
from fluiddyn.util import mpi
n = int(sys.argv[1])
p = Simul.create_default_params()
p.oper.nx = p.oper.ny = p.oper.nz = n
p.oper.Lx = p.oper.Ly = p.oper.Lz = 2 * np.pi
p.oper.type_fft = "fft3d.mpi_with_fftw1d" if mpi.nb_proc > 1 else "fft3d.with_fftw3d"
p.nu_2 = 1.0 / 1600
p.time_stepping.t_end = 5.0
p.time_stepping.type_time_scheme = "RK4"
p.init_fields.type = "in_script"
p.output.HAS_TO_SAVE = False
p.output.sub_directory = "fluidsim-runs"
p.short_name_type_run = f"tg{n}"
p.NEW_DIR_RESULTS = True
p.output.periods_print.print_stdout = 0
sim = Simul(p)
X, Y, Z = sim.oper.get_XYZ_loc()
vx = np.sin(X) * np.cos(Y) * np.cos(Z)
vy = -np.cos(X) * np.sin(Y) * np.cos(Z)
vz = 0 * X
sim.state.init_statephys_from(vx=vx, vy=vy, vz=vz)
sim.state.statespect_from_statephys()
sim.state.statephys_from_statespect()
E0 = sim.output.compute_energy()
ts = sim.time_stepping
_clf = ts.compute_time_increment_CLF
def clf_landing():
    _clf()
    # Land exactly on t_end (the last step shortened), so E is E(5), not E(5 + dt).
    if ts.t + ts.deltat > 5.0:
        ts.deltat = 5.0 - ts.t
ts.compute_time_increment_CLF = clf_landing
t0 = time.perf_counter()
sim.time_stepping.start()
wall = time.perf_counter() - t0
E = sim.output.compute_energy()
if mpi.rank == 0:
    print(f"n={n} E0={E0:.6f} t={sim.time_stepping.t:.4f} it={sim.time_stepping.it} E5={E:.6f} err={100*(E/0.1184-1):+.3f}% wall={wall:.1f}s")
