#include "image_library.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef SG_IMAGES_LIBRARY
#define SG_IMAGES_LIBRARY "libsg_images.so"
#endif

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static void *library;
static const char *library_path;
static char load_error[512];

static void load(void)
{
    const char *path = getenv("SG_IMAGES_LIBRARY");
    library_path = path && *path ? path : SG_IMAGES_LIBRARY;
    /* RTLD_LOCAL: its copies of sg_fail and the temporary-file helpers
     * stay its own */
    library = dlopen(library_path, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        const char *why = dlerror();
        snprintf(load_error, sizeof load_error, "%s", why ? why : "cannot be loaded");
    }
}

void *sg_image_library_symbol(const char *name, SgError *err)
{
    pthread_once(&load_once, load);
    if (!library)
        return sg_fail(err, "image support: %s (make builds it)", load_error), NULL;
    void *f = dlsym(library, name);
    if (!f)
        sg_fail(err, "image support (%s): no %s in it", library_path, name);
    return f;
}
