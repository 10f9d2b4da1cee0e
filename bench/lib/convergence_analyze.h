/* `convergence analyze` (bench/convergence.c, for bench/sections/
 * 60-convergence.sh), in the bench library (libbench.a) so that
 * tests/test_bench_convergence.c can run it on synthetic curves.
 *
 *   analyze NAME RUNDIR SEEDS TABLEDIR [--modes A,B,...] [--compare X:Y]...
 *           [--size WxH] [--ref-relmse X] [--ref-mse8 Y] [--ref-mse Z]
 *           [--ref-spp N] [--ref-seconds S] [--ref-state TEXT]
 *
 * reads RUNDIR/MODE-SEED.csv (render --log) for seeds 1..SEEDS and the modes
 * of --modes, the first of which is the baseline; without --modes, the modes
 * that have such files, bsdf first, then skeleton, guided, openpgl, then any
 * other in name order (bsdf must be among them). A mode whose runs all
 * failed keeps its columns, with "-". Writes each mode's mean curve
 * RUNDIR/MODE.mean.dat (seconds spp relmse mse8 mse) and RUNDIR/levels.txt
 * ("relmse L1 L2 mse8 L1 L2 mse L1 L2"); appends one markdown row per level
 * to TABLEDIR/table2-{relmse,mse8,mse}.md and one row to
 * TABLEDIR/{equal-time,reference}.md, and for every mode whose runs trained
 * a field (the EXR attribute sg:training_passes > 0, i.e. openpgl) one row to
 * TABLEDIR/training.md; each table's header goes to TABLEDIR/TABLE.head
 * (rewritten every time: one table, one list of modes). One line goes to
 * TABLEDIR/headline.tsv: scene, image, relMSE level, bsdf s, guided s,
 * guided speed-up, skeleton speed-up, and where openpgl ran, openpgl s,
 * openpgl speed-up, guided over openpgl.
 *
 * --compare X:Y adds to the time-to-level tables a column with the speed-up
 * of X over Y (Y seconds / X seconds, > 1: X is faster); by default
 * guided:openpgl when both modes are there. With --modes bsdf,skeleton,guided
 * the tables are those of the three-mode benchmark, plus the MSE ones. */
#ifndef SG_CONVERGENCE_ANALYZE_H
#define SG_CONVERGENCE_ANALYZE_H

#include "error.h"

#define SG_ANALYZE_MAX_MODES 8
#define SG_ANALYZE_MAX_COMPARE 4

/* argv as the program's: argv[1] is "analyze", argv[2] NAME. 0 on success. */
int sg_convergence_analyze(int argc, char **argv, SgError *err);

#endif
