/* Linked into every test binary: makes Criterion's start-up cheap.
 *
 * Criterion 2.4 finds its tests, suites and hooks by walking every loaded
 * shared object with dl_iterate_phdr and opening and mapping each one's
 * file to read its section headers (src/compat/section-elf.c), ten walks a
 * process, and it starts one process per test. Our test binaries load some
 * 40 shared objects (270 once a test reads or writes an image and
 * OpenImageIO's dependencies come), so these walks cost more CPU than most
 * tests' own work. Tests and hooks live only in the
 * executable and in libcriterion itself: this definition, which the
 * dynamic linker prefers to libc's, shows a callback that lives in
 * libcriterion those two objects alone, and passes every other caller (the
 * C++ unwinder, the sanitizers) to the next definition unchanged. */
#include <criterion/criterion.h>
#include <dlfcn.h>
#include <link.h>
#include <stdbool.h>
#include <stdint.h>

typedef int (*PhdrCallback)(struct dl_phdr_info *, size_t, void *);
typedef int (*IteratePhdr)(PhdrCallback, void *);

typedef struct CriterionsOwn {
    PhdrCallback callback;
    void *data;
    uintptr_t criterion_code; /* an address inside libcriterion */
    int seen;
} CriterionsOwn;

static bool holds(const struct dl_phdr_info *info, uintptr_t address)
{
    for (int i = 0; i < info->dlpi_phnum; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        uintptr_t start = info->dlpi_addr + ph->p_vaddr;
        if (ph->p_type == PT_LOAD && address >= start && address - start < ph->p_memsz)
            return true;
    }
    return false;
}

/* The executable (always reported first) and libcriterion. */
static int criterions_own(struct dl_phdr_info *info, size_t size, void *data)
{
    CriterionsOwn *c = data;
    if (c->seen++ == 0 || holds(info, c->criterion_code))
        return c->callback(info, size, c->data);
    return 0;
}

static uintptr_t object_of(const void *address)
{
    Dl_info info;
    return dladdr(address, &info) ? (uintptr_t)info.dli_fbase : 0;
}

int dl_iterate_phdr(PhdrCallback callback, void *data)
{
    static _Atomic(IteratePhdr) next_definition;
    IteratePhdr next = next_definition;
    if (!next) /* threads that race here all store the same value */
        next_definition = next = (IteratePhdr)dlsym(RTLD_NEXT, "dl_iterate_phdr");
    const void *criterion_code = (const void *)criterion_run_all_tests;
    uintptr_t criterion = object_of(criterion_code);
    if (criterion && object_of((const void *)callback) == criterion) {
        CriterionsOwn c = {callback, data, (uintptr_t)criterion_code, 0};
        return next(criterions_own, &c);
    }
    return next(callback, data);
}
