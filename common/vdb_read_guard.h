/* What keeps a hostile .vdb file from taking the process down while
 * OpenVDB reads it, in one place (common/vdb_read_guard.cpp): two
 * process-wide interpositions, made explicit here and checked by a test.
 *
 * 1. The global operator new/delete go through malloc/free, and refuse
 *    (std::bad_alloc, as the standard says) a request larger than the
 *    machine's memory or than the current thread's read cap. OpenVDB trusts
 *    the sizes stored in a file, and the sanitizer runtimes would abort in
 *    their own operator new where the standard throws.
 * 2. OpenVDB's two chunk readers (io::unzipFromStream, io::bloscFromStream)
 *    are defined again here: each checks the chunk's stated length against
 *    the buffer before calling the library's own (found by dlsym(RTLD_NEXT)).
 *    OpenVDB 10 reads an uncompressed chunk of whatever length the file says
 *    into a buffer sized for the node: a heap overflow (found by fuzz_medium_vdb).
 *
 * Both hold only while this object is linked into the program and wins
 * symbol resolution (a dynamic libopenvdb, as Debian's): an OpenVDB upgrade
 * (new mangled names) or a static link could silently drop them, so
 * sg_vdb_read_guard_check says whether they are in effect, and
 * tests/test_vdb_read_guard.c fails loudly when they are not. */
#ifndef SG_VDB_READ_GUARD_H
#define SG_VDB_READ_GUARD_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Sets this thread's cap on one allocation (SIZE_MAX: none) and returns
 * the previous one: the medium reader sets it to what the file can hold. */
size_t sg_vdb_read_cap_set(size_t cap);

/* True when both interpositions are in effect in this process: operator new
 * is ours and honours the cap, and the chunk readers that OpenVDB's
 * templates and the dynamic linker resolve are ours, with the library's own
 * found behind them. Otherwise false, saying which is missing. */
bool sg_vdb_read_guard_check(SgError *err);

#ifdef __cplusplus
}
#endif
#endif
