/* Scene loading time: build/release/bench/scene_load SCENE [RUNS]
 * prints "triangles T materials M lights L best_seconds S" (best of RUNS). */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "scene_load.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: scene_load SCENE [RUNS]\n");
        return 2;
    }
    int runs = argc == 3 ? atoi(argv[2]) : 3;
    if (runs < 1)
        runs = 1;
    double best = 1e30;
    SgScene *last = NULL;
    for (int r = 0; r < runs; r++) {
        SgError err = {0};
        double t0 = now();
        SgScene *s = sg_scene_load(argv[1], &err);
        double t = now() - t0;
        if (!s) {
            sg_error_print("scene_load", &err);
            return 1;
        }
        best = t < best ? t : best;
        sg_scene_free(last);
        last = s;
    }
    printf("triangles %u materials %u lights %u warnings %u best_seconds %.3f\n",
           last->triangle_count, last->material_count, last->light_count, last->warning_count,
           best);
    sg_scene_free(last);
    return 0;
}
