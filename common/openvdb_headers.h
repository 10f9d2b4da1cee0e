// OpenVDB's headers, for the two C++ files that use them (medium_vdb.cpp,
// vdb_read_guard.cpp). OpenVDB reads the raw bytes of a file into bool tile
// values and flags (RootNode::readTopology, readCompressedValues), so a
// corrupt file gives a bool holding 54: undefined behaviour in OpenVDB's own
// templates, instantiated by its includers, harmless in practice (any
// non-zero byte reads as true) and not ours to fix. The sanitizers' bool
// check is off for those templates: under clang here, under gcc by
// -fno-sanitize=bool on the includers (Makefile).
#ifndef SG_OPENVDB_HEADERS_H
#define SG_OPENVDB_HEADERS_H

#if defined(__clang__)
#pragma clang attribute push(__attribute__((no_sanitize("bool"))), apply_to = function)
#endif
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/io/io.h>
#include <openvdb/openvdb.h>
#if defined(__clang__)
#pragma clang attribute pop
#endif

#endif
