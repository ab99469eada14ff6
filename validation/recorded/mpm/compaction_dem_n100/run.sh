#!/bin/sh
# Scene 3 (Section 6.2, Figs. 10–15) at 100 discs: the packing prepared by the frictionless DEM
# ("compress"), compacted to Φ = 0.97 at λ = 0 and 3 MPa (one thread each), then the fits.
# Wall time on the shared 2-core machine: 37 min (λ = 0) and 53 min (λ = 3), 1398 and 2228 s CPU.
# Usage, from the repository root: sh validation/recorded/mpm/compaction_dem_n100/run.sh target/release/mcdem
set -e
bin=${1:-target/release/mcdem}
here=validation/recorded/mpm/compaction_dem_n100
for lam in 0 3; do
  RAYON_NUM_THREADS=1 $bin mpm validation/cases/mpm/compaction_n100_lambda$lam.json --out $here/lambda$lam --vtk-every 250 2> $here/lambda$lam.log
done
# The time-step check: λ = 0 at Δt = 10 µs (the record stops at Φ = 0.867, cut short for machine time).
RAYON_NUM_THREADS=1 $bin mpm validation/cases/mpm/compaction_n100_lambda0_dt10us.json --out $here/lambda0_dt10us 2> $here/lambda0_dt10us.log
$bin mpm-fit $here/lambda0 $here/lambda3 --out $here/fit_phi0_data
$bin mpm-fit $here/lambda0 $here/lambda3 --phi0 0.8 --out $here/fit_phi0_0.8
