"""ESyS-Particle's step on the lattice spall's BM_Lattice_Step steps: an n^3 cubic block of
rotating spheres (one per voxel), each bonded to its six neighbours by a brittle beam
(BrittleBeamPrms, the parallel bond ESyS offers), stepped `steps` times. Prints the rate.

    mpirun --allow-run-as-root --oversubscribe -np WORKERS+1 esysparticle esys_block.py N STEPS WORKERS

ESyS 2.3.5 runs a master and WORKERS workers, one MPI process each (tools/bench_peers.sh)."""
import sys
import time

from esys.lsm import BrittleBeamPrms, LsmMpi
from esys.lsm.geometry import ConnectionFinder, CubicBlock
from esys.lsm.util import BoundingBox, Vec3

n, steps, workers = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
sim = LsmMpi(numWorkerProcesses=workers, mpiDimList=[workers, 1, 1])
sim.initNeighbourSearch(particleType="RotSphere", gridSpacing=2.5, verletDist=0.2)
sim.setSpatialDomain(BoundingBox(Vec3(-2, -2, -2), Vec3(n + 2, n + 2, n + 2)))
sim.setTimeStepSize(1.0e-4)
sim.setNumTimeSteps(steps)
block = CubicBlock(dimCount=[n, n, n], radius=0.5)  # touching spheres one spacing apart
sim.createParticles(block)
sim.createConnections(ConnectionFinder(maxDist=0.005, bondTag=1, pList=block))
sim.createInteractionGroup(BrittleBeamPrms(name="bonds", youngsModulus=1.0e5, poissonsRatio=0.25, cohesion=1.0e3,
                                           tanAngle=1.0, tag=1))
start = time.time()
sim.run()
elapsed = time.time() - start
print(f"esys-particle {n}^3, {workers} worker(s): {steps} steps in {elapsed:.2f} s, {n ** 3 * steps / elapsed / 1e6:.2f} M particle-steps/s")
