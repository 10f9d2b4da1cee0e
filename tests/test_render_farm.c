/* The render farm (scripts/slurm-render.sh, render --shard, bin/merge)
 * against a real one-node Slurm cluster started for the test
 * (tests/slurm-cluster.sh; skipped, saying why, where it cannot start),
 * and without Slurm. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image_io.h"
#include "support_files.h"

#define SCENE "data/corridor/corridor.json"

static char g_cluster[4096];
typedef struct Image {
    int w, h;
    float *rgb;
    long spp;
} Image;

static Image load(const char *path)
{
    Image im = {0};
    SgError err = {0};
    cr_assert(sg_image_read(path, &im.w, &im.h, &im.rgb, &err), "%s", err.message);
    char buf[64];
    cr_assert(sg_image_read_attribute(path, "spp", buf, sizeof buf, &err), "%s", err.message);
    im.spp = atol(buf);
    return im;
}

/* The image DIR/NAME (printf-style name). */
static Image load_at(const char *dir, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static Image load_at(const char *dir, const char *fmt, ...)
{
    char name[256], path[4500];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(name, sizeof name, fmt, ap);
    va_end(ap);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return load(path);
}

/* Mean of merged - other over pixels and channels, and its standard
 * error from the differences' spread (pixels are independent). */
static void mean_difference(const Image *a, const Image *b, double *mean, double *se)
{
    size_t n = (size_t)a->w * a->h * 3;
    double s = 0, s2 = 0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)a->rgb[i] - b->rgb[i];
        s += d;
        s2 += d * d;
    }
    *mean = s / n;
    *se = sqrt(fmax(0.0, s2 / n - *mean * *mean) / (n - 1));
}

/* scripts/slurm-render.sh on the corridor with the programs under test and
 * the options given (printf-style): its exit status, its stderr in err. */
static int slurm_render(char err[4096], const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int slurm_render(char err[4096], const char *fmt, ...)
{
    char options[8192], cmd[16384];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(options, sizeof options, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "bash scripts/slurm-render.sh " SCENE " --bin %s %s", sg_test_bin_dir(), options);
    return sg_test_run(cmd, err, 4096);
}

static void stop_cluster(void)
{
    if (!g_cluster[0])
        return;
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "bash tests/slurm-cluster.sh stop %s", g_cluster);
    sg_test_run(cmd, NULL, 0);
    g_cluster[0] = 0;
}

static void start_cluster(void)
{
    const char *tmp = sg_test_tmpdir();
    snprintf(g_cluster, sizeof g_cluster, "%s/cluster", tmp);
    char cmd[8192], err[2048] = "";
    snprintf(cmd, sizeof cmd, "bash tests/slurm-cluster.sh start %s >/dev/null", g_cluster);
    int status = sg_test_run(cmd, err, sizeof err);
    if (status == 77) {
        g_cluster[0] = 0;
        cr_skip_test("no Slurm cluster here: %s", err);
    }
    /* stopped at the end of the test, or at exit where an assertion ended it
     * (a Criterion .fini leaks 48 bytes inside libcriterion under LSan) */
    atexit(stop_cluster);
    cr_assert_eq(status, 0, "the cluster did not start: %s", err);
    char conf[4200];
    snprintf(conf, sizeof conf, "%s/slurm.conf", g_cluster);
    setenv("SLURM_CONF", conf, 1);
}

/* The farm's merged image is exactly the spp-weighted mean of its shards. */
static void check_exact_merge(const char *dir, int shards, long total_spp)
{
    Image merged = load_at(dir, "corridor.exr");
    cr_assert_eq(merged.spp, total_spp, "merged spp %ld, expected %ld", merged.spp, total_spp);
    size_t n = (size_t)merged.w * merged.h * 3;
    double *sum = calloc(n, sizeof *sum);
    long spp = 0;
    for (int k = 0; k < shards; k++) {
        Image s = load_at(dir, "shards/corridor-%d.exr", k);
        cr_assert(s.w == merged.w && s.h == merged.h);
        for (size_t i = 0; i < n; i++)
            sum[i] += (double)s.spp * s.rgb[i];
        spp += s.spp;
        free(s.rgb);
    }
    cr_assert_eq(spp, total_spp, "the shards hold %ld spp, expected %ld", spp, total_spp);
    size_t wrong = 0;
    for (size_t i = 0; i < n; i++)
        wrong += merged.rgb[i] != (float)(sum[i] / (double)spp);
    cr_assert_eq(wrong, 0, "%zu of %zu values differ from the spp-weighted mean of the shards", wrong, n);
    free(sum);
    free(merged.rgb);
}

Test(render_farm, four_shards_through_slurm_merge_exactly_and_survive_a_cancelled_shard)
{
    start_cluster();
    const char *tmp = sg_test_tmpdir();
    const char *bin = sg_test_bin_dir();
    char cmd[16384], err[4096];

    /* 1. four shards of a 32 spp render, merged */
    /* --training-passes goes to the precompute job's training alone (a
     * shard given it with its --field would refuse to start) */
    int status = slurm_render(
        err, "--shards 4 --out %s/farm --wait -- --spp 32 --size 48x36 --seed 7 --training-passes 128 >/dev/null", tmp);
    cr_assert_eq(status, 0, "slurm-render failed (%d): %s", status, err);
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/farm", tmp);
    check_exact_merge(dir, 4, 32);

    /* 2. it agrees with one process rendering the same 32 spp (guided: each
     * shard learned on its own, so equal in expectation, not in bits) */
    snprintf(cmd, sizeof cmd,
             "%s/render " SCENE " --cache %s/farm/importance.cache --spp 32 --size 48x36 --seed 7 -o %s/single.exr "
             "--quiet",
             bin, tmp, tmp);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    Image merged = load_at(tmp, "farm/corridor.exr"), single = load_at(tmp, "single.exr");
    double mean, se;
    mean_difference(&merged, &single, &mean, &se);
    cr_log_info("farm of 4 against one process: mean difference %.3g +- %.3g", mean, se);
    cr_assert(fabs(mean) < 3.0 * se, "merged and single-process images differ by %.3g (+- %.3g)", mean, se);
    cr_assert(se > 0.0, "the two images are identical: they cannot be independent renders");
    free(merged.rgb);
    free(single.rgb);

    /* 3. a shard cancelled while it runs leaves no file; --resume renders it
     * again, and the merge follows */
    /* long enough that shard 0 is caught running (some 2.5 s of passes
     * in a release build with two shards on two cores; as long under the
     * sanitizers with fewer), short enough not to hold up the other
     * suites: the three other shards, the rerun and the check render all
     * scale with it */
    const int long_spp = getenv("SG_SANITIZED") ? 400 : 1200;
    cr_assert_eq(slurm_render(err, "--shards 4 --out %s/farm2 -- --spp %d --size 48x36 --seed 3 --training-passes 128 >/dev/null", tmp,
                              long_spp), 0,
                 "%s", err);
    char job[64] = "";
    for (int i = 0; i < 400 && !job[0]; i++) { /* shard 0 running */
        FILE *p = popen("squeue -h -n corridor-shards -t RUNNING -o '%i' | grep '_0$'", "r");
        cr_assert_not_null(p);
        if (!fgets(job, sizeof job, p))
            job[0] = 0;
        pclose(p);
        job[strcspn(job, "\n")] = 0;
        if (!job[0])
            usleep(100000);
    }
    cr_assert(job[0], "shard 0 never ran");
    usleep(300000); /* into its passes */
    snprintf(cmd, sizeof cmd, "scancel %s", job);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    /* the merge can no longer run: Slurm drops it (kill-on-invalid-dep);
     * the other shards finish (up to 5 minutes: under AddressSanitizer on a
     * loaded machine 60 s did not always do) */
    for (int i = 0; i < 3000; i++) {
        FILE *p = popen("squeue -h -n corridor-shards,corridor-merge -o '%i'", "r");
        char line[256];
        bool any = p && fgets(line, sizeof line, p);
        if (p)
            pclose(p);
        if (!any)
            break;
        usleep(100000);
    }
    snprintf(cmd, sizeof cmd, "test ! -e %s/farm2/shards/corridor-0.exr && test ! -e %s/farm2/corridor.exr && "
             "! ls -a %s/farm2/shards | grep -q tmp", tmp, tmp, tmp);
    cr_assert_eq(sg_test_run(cmd, NULL, 0), 0, "a cancelled shard left a file behind (or the merge ran without it)");
    snprintf(cmd, sizeof cmd, "ls %s/farm2/shards | wc -l | grep -qx 3", tmp);
    cr_assert_eq(sg_test_run(cmd, NULL, 0), 0, "the three other shards should have finished");

    /* the merge refuses what is left, and writes nothing */
    snprintf(cmd, sizeof cmd, "%s/merge %s/farm2/shards/corridor-1.exr %s/farm2/shards/corridor-2.exr "
             "%s/farm2/shards/corridor-3.exr -o %s/partial.exr", bin, tmp, tmp, tmp, tmp);
    status = sg_test_run(cmd, err, sizeof err);
    cr_assert_eq(status, 1, "merge of 3 of 4 shards: exit %d (%s)", status, err);
    cr_assert(strstr(err, "missing"), "the refusal does not say what is missing: %s", err);
    char path[4200];
    snprintf(path, sizeof path, "%s/partial.exr", tmp);
    cr_assert(!sg_test_exists(path), "a refused merge left %s", path);

    snprintf(cmd, sizeof cmd, "bash scripts/slurm-render.sh --resume %s/farm2 --wait >/dev/null", tmp);
    status = sg_test_run(cmd, err, sizeof err);
    cr_assert_eq(status, 0, "--resume failed (%d): %s", status, err);
    snprintf(dir, sizeof dir, "%s/farm2", tmp);
    check_exact_merge(dir, 4, long_spp);

    /* the rerun shard is the shard: the same pixels as rendering it here
     * (guided learns: every shard renders with the field the precompute
     * job trained) */
    snprintf(cmd, sizeof cmd,
             "%s/render " SCENE " --cache %s/farm2/importance.cache --field %s/farm2/corridor.field --spp %d "
             "--size 48x36 --seed 3 --shard 0/4 "
             "-o %s/shard0.exr --quiet && idiff -q -fail 0 -warn 0 %s/shard0.exr %s/farm2/shards/corridor-0.exr",
             bin, tmp, tmp, long_spp, tmp, tmp, tmp);
    status = sg_test_run(cmd, err, sizeof err);
    cr_assert_eq(status, 0, "shard 0 rendered again differs (%d): %s", status, err);
    stop_cluster();
}

/* Without Slurm the script runs the same steps here; in bsdf mode, whose
 * passes learn nothing, the shards' passes are the single render's passes:
 * the merged image is that render's, to float rounding. */
Test(render_farm, local_shards_are_the_single_render_in_bsdf_mode)
{
    const char *tmp = sg_test_tmpdir();
    const char *bin = sg_test_bin_dir();
    char cmd[16384], err[4096];
    int status = slurm_render(err, "--shards 3 --out %s/local --local -- --sampling bsdf --spp 10 --size 48x36 --seed 5 "
                                   ">/dev/null", tmp);
    cr_assert_eq(status, 0, "slurm-render --local failed (%d): %s", status, err);
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/local", tmp);
    check_exact_merge(dir, 3, 10); /* 4 + 3 + 3 passes */
    snprintf(cmd, sizeof cmd, "%s/render " SCENE " --sampling bsdf --spp 10 --size 48x36 --seed 5 -o %s/one.exr --quiet",
             bin, tmp);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 0, "%s", err);
    Image merged = load_at(tmp, "local/corridor.exr"), one = load_at(tmp, "one.exr");
    size_t n = (size_t)one.w * one.h * 3;
    double worst = 0;
    for (size_t i = 0; i < n; i++)
        worst = fmax(worst, fabs((double)merged.rgb[i] - one.rgb[i]) / fmax(1e-6, fabs((double)one.rgb[i])));
    cr_log_info("3 local shards against one bsdf render: worst relative difference %.3g", worst);
    cr_assert(worst < 1e-5, "the shards' passes are not the single render's: relative difference %.3g", worst);
    free(merged.rgb);
    free(one.rgb);
}

/* A slurm.conf whose controller is not running (nothing listens on port 1
 * of the loopback): `scontrol ping` says DOWN at once. Where Slurm is not
 * installed, the script sees no controller either. */
static void no_controller(const char *tmp)
{
    char conf[4200];
    snprintf(conf, sizeof conf, "%s/slurm.conf", tmp);
    sg_test_write(tmp, "slurm.conf",
                  "ClusterName=none\nSlurmctldHost=localhost(127.0.0.1)\nSlurmctldPort=1\n"
                  "NodeName=localhost CPUs=1\nPartitionName=all Nodes=localhost\n");
    setenv("SLURM_CONF", conf, 1);
}

/* Slurm installed but no controller answering (a workstation): the shards
 * run here, one line says so, and the image is the farm's. */
Test(render_farm, no_controller_runs_the_shards_here)
{
    const char *tmp = sg_test_tmpdir();
    no_controller(tmp);
    char err[4096];
    int status = slurm_render(err, "--shards 3 --out %s/here -- --sampling bsdf --spp 7 --size 24x18 --seed 2 >/dev/null",
                              tmp);
    cr_assert_eq(status, 0, "slurm-render without a controller failed (%d): %s", status, err);
    /* the script's one line, then merge's summary */
    const char *said = strstr(err, "slurm-render: ");
    cr_assert(said && !strstr(said + 1, "slurm-render: "), "one line should say where the shards ran: %s", err);
    cr_assert(strstr(said, "no Slurm controller answers") || strstr(said, "not installed"), "said: %s", err);
    cr_assert(strstr(said, "running the 3 shards here\n"), "said: %s", err);
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/here", tmp);
    check_exact_merge(dir, 3, 7);
}

/* --slurm insists on the cluster: without one it fails in one line before
 * writing anything. */
Test(render_farm, slurm_without_a_controller_fails_and_writes_nothing)
{
    const char *tmp = sg_test_tmpdir();
    no_controller(tmp);
    char err[4096], path[4200];
    int status = slurm_render(err, "--shards 3 --out %s/farm --slurm -- --sampling bsdf --spp 7", tmp);
    cr_assert_eq(status, 1, "--slurm without a controller: exit %d (%s)", status, err);
    cr_assert_eq(sg_test_count_lines(err), 1, "not one line: %s", err);
    cr_assert(strstr(err, "slurm-render: --slurm: "), "said: %s", err);
    snprintf(path, sizeof path, "%s/farm", tmp);
    cr_assert(!sg_test_exists(path), "a refused --slurm left %s", path);
    /* one or the other */
    status = slurm_render(err, "--shards 3 --out %s/farm --slurm --local", tmp);
    cr_assert_eq(status, 2, "--slurm --local: exit %d (%s)", status, err);
    cr_assert(!sg_test_exists(path), "a usage error left %s", path);
}

Test(render_farm, render_refuses_a_shard_it_cannot_render)
{
    const char *tmp = sg_test_tmpdir();
    const char *bin = sg_test_bin_dir();
    char cmd[8192], err[2048];
    const char *bad[] = {"4/4", "-1/4", "1/0", "2", "a/b", "1/70000"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s/render " SCENE " --sampling bsdf --spp 4 --shard %s -o %s/x.exr", bin, bad[i],
                 tmp);
        cr_assert_eq(sg_test_run(cmd, err, sizeof err), 2, "--shard %s: %s", bad[i], err);
        cr_assert(strstr(err, "--shard"), "--shard %s said: %s", bad[i], err);
    }
    /* 2 spp in 4 shards: shard 3 has no pass */
    snprintf(cmd, sizeof cmd, "%s/render " SCENE " --sampling bsdf --spp 2 --shard 3/4 --size 8x6 -o %s/x.exr", bin, tmp);
    cr_assert_eq(sg_test_run(cmd, err, sizeof err), 1, "%s", err);
    cr_assert(strstr(err, "no pass"), "said: %s", err);
    char path[4200];
    snprintf(path, sizeof path, "%s/x.exr", tmp);
    cr_assert(!sg_test_exists(path), "a refused render left %s", path);
}
