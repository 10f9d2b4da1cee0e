// The interpositions that guard OpenVDB's reading of hostile files: see
// vdb_read_guard.h for what they are, why, and how they are checked.
#include "vdb_read_guard.h"


#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <new>
#include <sstream>
#include <string>

#include <dlfcn.h>
#include <unistd.h>

#include "openvdb_headers.h"

// OpenVDB trusts the sizes stored in a file: a corrupt or truncated file can
// ask operator new for terabytes. The standard says such a request throws
// std::bad_alloc, which sg_medium_read turns into a one-line error, but
// sanitizer runtimes abort in their own operator new instead. Routing the
// global new/delete through malloc/free keeps the standard behaviour in
// every build. A request larger than the machine's memory is refused before
// it reaches the allocator, so no sanitizer has anything to say about it.
//
// Below the machine's size a corrupt length can still ask for gigabytes
// that are then zero-filled (a metadata string of 1.6 GB in a 10 kB file),
// so while a medium is read, one allocation may not exceed what the file
// can hold plus room for OpenVDB's fixed node tables (this thread only).
static thread_local std::size_t sg_read_allocation_cap = SIZE_MAX;
// Allocations served by this operator new (for sg_vdb_read_guard_check).
static thread_local std::size_t sg_guard_allocations = 0;

// GCC sees free() inlined where OpenVDB's `new` is visible and cannot know
// that this `new` is malloc: its mismatched-new-delete warning is wrong here.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
static bool sg_allocation_possible(std::size_t size)
{
    static const std::size_t physical = [] {
        long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
        return pages > 0 && page > 0 ? (std::size_t)pages * (std::size_t)page : SIZE_MAX;
    }();
    return size <= physical && size <= sg_read_allocation_cap;
}


void *operator new(std::size_t size)
{
    sg_guard_allocations++;
    if (sg_allocation_possible(size))
        if (void *p = std::malloc(size ? size : 1))
            return p;
    throw std::bad_alloc();
}
void *operator new[](std::size_t size) { return ::operator new(size); }
void *operator new(std::size_t size, const std::nothrow_t &) noexcept
{
    return sg_allocation_possible(size) ? std::malloc(size ? size : 1) : nullptr;
}
void *operator new[](std::size_t size, const std::nothrow_t &) noexcept
{
    return ::operator new(size, std::nothrow);
}
void operator delete(void *p) noexcept { std::free(p); }
void operator delete[](void *p) noexcept { std::free(p); }
void operator delete(void *p, std::size_t) noexcept { std::free(p); }
void operator delete[](void *p, std::size_t) noexcept { std::free(p); }
void operator delete(void *p, const std::nothrow_t &) noexcept { std::free(p); }
void operator delete[](void *p, const std::nothrow_t &) noexcept { std::free(p); }

// OpenVDB 10 reads an uncompressed chunk (a negative size before it) of
// whatever length the file states into a buffer sized for the node: a
// corrupt file overflows the heap (found by fuzz_medium_vdb). Its two chunk
// readers are replaced here by ones that check that length first and then
// hand over to the library's own (the calls from OpenVDB's templates, all
// instantiated in this file, bind to these definitions).
#define SG_STR2(x) #x
#define SG_STR(x) SG_STR2(x)
namespace {
using ChunkReader = void (*)(std::istream &, char *, size_t);

// The library's function: the next definition of the same symbol.
ChunkReader library_chunk_reader(const char *name, std::size_t name_length)
{
    const std::string version = SG_STR(OPENVDB_VERSION_NAME);
    const std::string symbol = "_ZN7openvdb" + std::to_string(version.size()) + version + "2io" +
                               std::to_string(name_length) + name + "ERSiPcm";
    return reinterpret_cast<ChunkReader>(dlsym(RTLD_NEXT, symbol.c_str()));
}

void read_chunk_checked(ChunkReader original, const char *name, std::istream &is, char *data,
                        size_t numBytes)
{
    if (!original)
        OPENVDB_THROW(openvdb::RuntimeError, "cannot find OpenVDB's " << name);
    std::streampos start = is.tellg();
    openvdb::Int64 size = 0;
    is.read(reinterpret_cast<char *>(&size), sizeof size);
    if (!is.good() || start == std::streampos(-1))
        OPENVDB_THROW(openvdb::RuntimeError, "stream failure reading the size of a chunk");
    if (size <= 0 && (size == INT64_MIN || (std::uint64_t)(-size) != numBytes))
        OPENVDB_THROW(openvdb::RuntimeError, "expected a " << numBytes << "-byte chunk, the file says "
                                                           << (size == INT64_MIN ? 0 : -size));
    is.seekg(start);
    original(is, data, numBytes);
}
} // namespace

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
namespace io {
void unzipFromStream(std::istream &is, char *data, size_t numBytes)
{
    static const ChunkReader original = library_chunk_reader("unzipFromStream", 15);
    read_chunk_checked(original, "unzipFromStream", is, data, numBytes);
}
void bloscFromStream(std::istream &is, char *data, size_t numBytes)
{
    static const ChunkReader original = library_chunk_reader("bloscFromStream", 15);
    read_chunk_checked(original, "bloscFromStream", is, data, numBytes);
}
} // namespace io
} // namespace OPENVDB_VERSION_NAME
} // namespace openvdb


extern "C" size_t sg_vdb_read_cap_set(size_t cap)
{
    size_t previous = sg_read_allocation_cap;
    sg_read_allocation_cap = cap;
    return previous;
}

namespace {
// The symbol the dynamic linker gives for an OpenVDB chunk reader.
void *resolved_chunk_reader(const char *name, std::size_t name_length)
{
    const std::string version = SG_STR(OPENVDB_VERSION_NAME);
    const std::string symbol = "_ZN7openvdb" + std::to_string(version.size()) + version + "2io" +
                               std::to_string(name_length) + name + "ERSiPcm";
    return dlsym(RTLD_DEFAULT, symbol.c_str());
}
} // namespace

extern "C" bool sg_vdb_read_guard_check(SgError *err)
{
    // operator new: ours counts, and refuses beyond the cap
    std::size_t before = sg_guard_allocations;
    delete[] new char[16];
    if (sg_guard_allocations == before)
        return sg_fail(err, "vdb read guard: the global operator new is not this program's");
    std::size_t previous = sg_vdb_read_cap_set(1000);
    char *over = new (std::nothrow) char[2000];
    sg_vdb_read_cap_set(previous);
    if (over) {
        delete[] over;
        return sg_fail(err, "vdb read guard: operator new ignores the read cap");
    }
    // the chunk readers: what the process resolves refuses a chunk longer
    // than its buffer before reading a byte of it (the library's reads it,
    // and complains after: into a buffer made large enough here), and the
    // library's own is found behind it
    for (const char *name : {"unzipFromStream", "bloscFromStream"}) {
        auto resolved = reinterpret_cast<ChunkReader>(resolved_chunk_reader(name, 15));
        if (!resolved)
            return sg_fail(err, "vdb read guard: openvdb::io::%s resolves to nothing (a new OpenVDB version name?)",
                           name);
        if (!library_chunk_reader(name, 15))
            return sg_fail(err, "vdb read guard: OpenVDB's own %s is not found behind ours", name);
        std::string bytes(8 + 64, '\x5a');
        const std::int64_t stated = -17; /* uncompressed, 17 bytes, for a 16-byte buffer */
        std::memcpy(&bytes[0], &stated, sizeof stated);
        std::istringstream is(bytes);
        char buffer[64] = {0};
        try {
            resolved(is, buffer, 16);
        } catch (const openvdb::Exception &) {
            /* both throw: the library's only after it has read the chunk */
        }
        if (buffer[16] != 0)
            return sg_fail(err, "vdb read guard: openvdb::io::%s reads a chunk longer than its buffer: the "
                                "checked reader is not in effect",
                           name);
    }
    return true;
}
