// The one place that speaks OpenVDB: SgMedium <-> a .vdb file holding a
// BoolGrid named "medium" (active voxels = medium) and file metadata with
// the lights, camera and input identity. C++ stays inside this file.
#include "medium.h"


#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <ios>
#include <new>
#include <stdexcept>
#include <string>

#include "openvdb_headers.h"
#include "output_file.h"
#include "vdb_read_guard.h"

namespace {
// While a medium is read, one allocation may not exceed what the file can
// hold plus room for OpenVDB's fixed node tables (common/vdb_read_guard.h).
struct ReadAllocationCap {
    std::size_t previous;
    explicit ReadAllocationCap(std::size_t cap) : previous(sg_vdb_read_cap_set(cap)) {}
    ~ReadAllocationCap() { sg_vdb_read_cap_set(previous); }
};
} // namespace

namespace {

const char *const kFormat = "skeleton-guided medium 1";

std::string light_key(uint32_t light, const char *what)
{
    return "light_" + std::to_string(light) + "_" + what;
}

openvdb::BoolGrid::Ptr grid_from_medium(const SgMedium *m)
{
    const SgGrid &g = m->grid;
    auto grid = openvdb::BoolGrid::create(false);
    grid->setName(SG_MEDIUM_GRID_NAME);
    // Voxel (i,j,k) has its centre at origin + (i+0.5, j+0.5, k+0.5) * h,
    // which is where OpenVDB puts index point (i,j,k) under this transform.
    auto xform = openvdb::math::Transform::createLinearTransform(g.voxel_size);
    xform->postTranslate(openvdb::Vec3d(g.origin[0] + 0.5 * g.voxel_size,
                                        g.origin[1] + 0.5 * g.voxel_size,
                                        g.origin[2] + 0.5 * g.voxel_size));
    grid->setTransform(xform);
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    // Fill leaf by leaf (8^3 blocks): far faster than one accessor call per voxel.
    auto &tree = grid->tree();
    for (int bk = 0; bk < g.nz; bk += 8)
        for (int bj = 0; bj < g.ny; bj += 8)
            for (int bi = 0; bi < g.nx; bi += 8) {
                openvdb::BoolTree::LeafNodeType *leaf = nullptr;
                for (int k = bk; k < bk + 8 && k < g.nz; k++)
                    for (int j = bj; j < bj + 8 && j < g.ny; j++) {
                        const uint8_t *row = g.voxels + sg_grid_index(&g, 0, j, k);
                        for (int i = bi; i < bi + 8 && i < g.nx; i++) {
                            if (!row[i])
                                continue;
                            if (!leaf)
                                leaf = tree.touchLeaf(openvdb::Coord(bi, bj, bk));
                            leaf->setValueOn(openvdb::Coord(i, j, k), true);
                        }
                    }
            }
    tree.prune();
    return grid;
}

template <typename T> bool get_meta(const openvdb::MetaMap &meta, const char *name, T &out)
{
    auto p = meta.getMetadata<openvdb::TypedMetadata<T>>(name);
    if (!p)
        return false;
    out = p->value();
    return true;
}

bool finite3(const openvdb::Vec3d &v)
{
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

} // namespace

extern "C" bool sg_medium_write(const SgMedium *m, const char *path, SgError *err)
{
    char tmp[4200];
    sg_temp_path(path, tmp, sizeof tmp);
    try {
        openvdb::initialize();
        auto grid = grid_from_medium(m);
        grid->insertMeta("voxel_count", openvdb::Int64Metadata(
                                            (int64_t)grid->tree().activeVoxelCount()));
        openvdb::MetaMap meta;
        meta.insertMeta("sg_format", openvdb::StringMetadata(kFormat));
        meta.insertMeta("grid_dims",
                        openvdb::Vec3IMetadata(openvdb::Vec3i(m->grid.nx, m->grid.ny, m->grid.nz)));
        meta.insertMeta("resolution", openvdb::Int32Metadata(m->resolution));
        char hash[32];
        snprintf(hash, sizeof hash, "%016" PRIx64, m->geometry_hash);
        meta.insertMeta("geometry_hash", openvdb::StringMetadata(hash));
        meta.insertMeta("scene", openvdb::StringMetadata(m->scene_path));
        meta.insertMeta("light_count", openvdb::Int32Metadata((int32_t)m->light_count));
        for (uint32_t k = 0; k < m->light_count; k++) {
            const SgMediumLight &l = m->lights[k];
            meta.insertMeta(light_key(k, "position"),
                            openvdb::Vec3DMetadata(openvdb::Vec3d(l.position)));
            meta.insertMeta(light_key(k, "normal"), openvdb::Vec3DMetadata(openvdb::Vec3d(l.normal)));
            meta.insertMeta(light_key(k, "radiance"),
                            openvdb::Vec3DMetadata(openvdb::Vec3d(l.radiance[0], l.radiance[1],
                                                                  l.radiance[2])));
            meta.insertMeta(light_key(k, "power"), openvdb::DoubleMetadata(l.power));
            meta.insertMeta(light_key(k, "seed"),
                            openvdb::Vec3IMetadata(openvdb::Vec3i(l.seed[0], l.seed[1], l.seed[2])));
            if (l.outside) // only where there is one: files of closed scenes stay as they were
                meta.insertMeta(light_key(k, "outside"), openvdb::BoolMetadata(true));
            if (l.sun)
                meta.insertMeta(light_key(k, "sun"), openvdb::BoolMetadata(true));
        }
        if (m->outside_margin > 0)
            meta.insertMeta("outside_margin", openvdb::Int32Metadata(m->outside_margin));
        if (m->has_camera)
            meta.insertMeta("camera_position",
                            openvdb::Vec3DMetadata(openvdb::Vec3d(m->camera_position)));
        openvdb::GridPtrVec grids{grid};
        openvdb::io::File file(tmp);
        file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(grids, meta);
        file.close();
        // OpenVDB does not check its stream after writing: on a full disk
        // the file ends early and nothing says so. Read the grid back before
        // the file takes the target's name.
        bool complete = false;
        try {
            // what the file holds bounds what reading it may allocate
            FILE *f = std::fopen(tmp, "rb");
            long size = f && std::fseek(f, 0, SEEK_END) == 0 ? std::ftell(f) : -1;
            if (f)
                std::fclose(f);
            ReadAllocationCap cap(size >= 0 ? (std::size_t)size + ((std::size_t)64 << 20) : 0);
            openvdb::io::File check(tmp);
            check.open(false);
            openvdb::GridBase::Ptr back = check.readGrid(SG_MEDIUM_GRID_NAME);
            complete = back && back->activeVoxelCount() == grid->activeVoxelCount();
            check.close();
        } catch (const std::exception &) {
        }
        if (!complete)
            throw std::runtime_error("the file does not read back complete (disk full?)");
    } catch (const std::exception &e) {
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write VDB: %s", path, e.what());
    } catch (...) {
        std::remove(tmp);
        return sg_fail(err, "%s: cannot write VDB", path);
    }
    return sg_commit_temp(tmp, path, err);
}

namespace {

// The grid's placement: a uniform linear transform; our files keep voxel
// (i,j,k) at index (i,j,k) over grid_dims, a foreign file is shifted so
// that its active box starts at 0 (*shift).
bool place_grid(SgMedium *m, const openvdb::GridBase &base, const openvdb::MetaMap *meta, const char *path,
                openvdb::Coord *shift, SgError *err)
{
    const openvdb::math::Transform &xf = base.transform();
    if (!xf.isLinear() || !xf.hasUniformScale())
        return sg_fail(err, "%s: the medium grid's transform is not a uniform linear scale", path);
    double h = xf.voxelSize()[0];
    openvdb::Vec3d centre0 = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
    if (!(h > 0) || !std::isfinite(h) || !finite3(centre0))
        return sg_fail(err, "%s: the medium grid's transform is not finite", path);

    openvdb::CoordBBox active = base.evalActiveVoxelBoundingBox();
    if (active.empty())
        return sg_fail(err, "%s: the medium is empty (no active voxel)", path);
    openvdb::Vec3i dims;
    *shift = openvdb::Coord(0, 0, 0);
    if (!meta || !get_meta(*meta, "grid_dims", dims) || active.min().x() < 0 || active.min().y() < 0 ||
        active.min().z() < 0 || active.max().x() >= dims[0] || active.max().y() >= dims[1] ||
        active.max().z() >= dims[2]) {
        *shift = active.min();
        // in 64 bits: a corrupt file's box may span more than an int
        std::int64_t ext[3];
        for (int a = 0; a < 3; a++) {
            ext[a] = (std::int64_t)active.max()[a] - active.min()[a] + 1;
            if (ext[a] > (1 << 30))
                return sg_fail(err, "%s: the medium's active region is implausibly large "
                               "(%lld voxels along axis %d)", path, (long long)ext[a], a);
        }
        dims = openvdb::Vec3i((int)ext[0], (int)ext[1], (int)ext[2]);
    }
    double origin[3];
    for (int a = 0; a < 3; a++)
        origin[a] = centre0[a] + ((*shift)[a] - 0.5) * h;
    if (!sg_grid_init(&m->grid, dims[0], dims[1], dims[2], origin, h, err)) {
        char why[1024];
        std::snprintf(why, sizeof why, "%s", err ? err->message : "");
        if (err)
            err->failed = false;
        return sg_fail(err, "%s: %s", path, why);
    }
    return true;
}

// Active tiles (our files are pruned: the medium's inside is mostly tiles)
// row by row, then the leaves' active voxels: far faster than a value
// iterator over every voxel of the tiles.
template <typename GridT, typename On> void fill_active(SgGrid *g, const GridT &grid, openvdb::Coord shift, On on)
{
    auto set_box = [&](const openvdb::CoordBBox &box) {
        // 64-bit counters: a box may end at INT_MAX
        const std::size_t width = (std::size_t)((std::int64_t)box.max().x() - box.min().x() + 1);
        for (std::int64_t k = box.min().z(); k <= box.max().z(); k++)
            for (std::int64_t j = box.min().y(); j <= box.max().y(); j++)
                std::memset(g->voxels + sg_grid_index(g, box.min().x() - shift.x(), j - shift.y(), k - shift.z()),
                            1, width);
    };
    auto tile = grid.cbeginValueOn();
    tile.setMaxDepth(tile.getLeafDepth() - 1);
    for (; tile; ++tile)
        if (on(tile.getValue())) {
            openvdb::CoordBBox box;
            tile.getBoundingBox(box);
            set_box(box);
        }
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf)
        for (auto v = leaf->cbeginValueOn(); v; ++v)
            if (on(*v)) {
                const openvdb::Coord c = v.getCoord();
                g->voxels[sg_grid_index(g, c.x() - shift.x(), c.y() - shift.y(), c.z() - shift.z())] = 1;
            }
}

// Light k from voxelize's metadata, its seed shifted as the grid is.
bool read_light(const openvdb::MetaMap &meta, int k, openvdb::Coord shift, SgMediumLight &l, const char *path,
                SgError *err)
{
    openvdb::Vec3d pos, nrm, rad(0, 0, 0);
    openvdb::Vec3i seed;
    double power = 0;
    if (!get_meta(meta, light_key(k, "position").c_str(), pos) || !get_meta(meta, light_key(k, "normal").c_str(), nrm) ||
        !get_meta(meta, light_key(k, "seed").c_str(), seed) || !finite3(pos) || !finite3(nrm))
        return sg_fail(err, "%s: metadata of light %d is missing or invalid", path, k);
    get_meta(meta, light_key(k, "radiance").c_str(), rad);
    get_meta(meta, light_key(k, "power").c_str(), power);
    for (int a = 0; a < 3; a++) {
        l.position[a] = pos[a];
        l.normal[a] = nrm[a];
        l.radiance[a] = (float)rad[a];
        l.seed[a] = seed[a] - (seed[0] >= 0 ? shift[a] : 0);
    }
    l.power = std::isfinite(power) ? power : 0;
    bool outside = false;
    l.outside = get_meta(meta, light_key(k, "outside").c_str(), outside) && outside;
    bool sun = false;
    l.sun = get_meta(meta, light_key(k, "sun").c_str(), sun) && sun;
    return true;
}

// Metadata written by voxelize; absent in foreign files (no lights then).
bool read_metadata(SgMedium *m, const openvdb::MetaMap &meta, openvdb::Coord shift, const char *path, SgError *err)
{
    int32_t resolution = 0, count = 0;
    std::string text;
    if (get_meta(meta, "resolution", resolution))
        m->resolution = resolution;
    int32_t margin = 0;
    if (get_meta(meta, "outside_margin", margin) && margin > 0 && margin < 1 << 20)
        m->outside_margin = margin;
    if (get_meta(meta, "geometry_hash", text))
        m->geometry_hash = std::strtoull(text.c_str(), nullptr, 16);
    if (get_meta(meta, "scene", text))
        std::snprintf(m->scene_path, sizeof m->scene_path, "%s", text.c_str());
    openvdb::Vec3d cam;
    if (get_meta(meta, "camera_position", cam) && finite3(cam)) {
        m->has_camera = true;
        for (int a = 0; a < 3; a++)
            m->camera_position[a] = cam[a];
    }
    if (!get_meta(meta, "light_count", count) || count <= 0)
        return true;
    if (count > 1000000)
        return sg_fail(err, "%s: implausible light_count %d", path, (int)count);
    m->lights = static_cast<SgMediumLight *>(std::calloc((size_t)count, sizeof(SgMediumLight)));
    if (!m->lights)
        return sg_fail(err, "%s: out of memory", path);
    m->light_count = (uint32_t)count;
    for (int k = 0; k < count; k++)
        if (!read_light(meta, k, shift, m->lights[k], path, err))
            return false;
    return true;
}

// The medium from a stream that throws at the first read past the end.
bool read_stream(SgMedium *m, std::istream &in, const char *path, SgError *err)
{
    openvdb::io::Stream stream(in, false);
    openvdb::MetaMap::Ptr meta = stream.getMetadata();
    openvdb::GridPtrVecPtr grids = stream.getGrids();
    openvdb::GridBase::Ptr base =
        grids ? openvdb::findGridByName(*grids, SG_MEDIUM_GRID_NAME) : openvdb::GridBase::Ptr();
    if (!base)
        return sg_fail(err, "%s: no grid named \"%s\"", path, SG_MEDIUM_GRID_NAME);
    openvdb::Coord shift;
    if (!place_grid(m, *base, meta.get(), path, &shift, err))
        return false;
    if (auto bgrid = openvdb::gridPtrCast<openvdb::BoolGrid>(base)) {
        fill_active(&m->grid, *bgrid, shift, [](bool value) { return value; });
    } else if (auto mgrid = openvdb::gridPtrCast<openvdb::MaskGrid>(base)) {
        fill_active(&m->grid, *mgrid, shift, [](bool) { return true; });
    } else {
        sg_grid_release(&m->grid);
        return sg_fail(err, "%s: grid \"%s\" is of type %s, not bool or mask", path, SG_MEDIUM_GRID_NAME,
                       base->type().c_str());
    }
    if (meta && !read_metadata(m, *meta, shift, path, err)) {
        sg_medium_release(m);
        return false;
    }
    return true;
}

} // namespace

extern "C" bool sg_medium_read(SgMedium *m, const char *path, SgError *err)
{
    std::memset(m, 0, sizeof *m);
    FILE *probe = std::fopen(path, "rb");
    if (!probe)
        return sg_fail(err, "%s: cannot open: %s", path, std::strerror(errno));
    long file_size = std::fseek(probe, 0, SEEK_END) == 0 ? std::ftell(probe) : -1;
    std::fclose(probe);
    ReadAllocationCap cap(file_size >= 0 ? (std::size_t)file_size + ((std::size_t)64 << 20) : SIZE_MAX);
    try {
        openvdb::initialize();
        // Read as a stream that throws at the first read past the end:
        // OpenVDB's loops trust counts from the file (4 billion root tiles
        // in a 10 kB file) and io::File keeps reading a failed stream, so a
        // corrupt file took a minute to be refused. Everything is read now
        // (no delayed loading through a memory map that could fault later).
        std::ifstream in(path, std::ios_base::in | std::ios_base::binary);
        in.exceptions(std::ios_base::failbit | std::ios_base::badbit);
        return read_stream(m, in, path, err);
    } catch (const std::ios_base::failure &) {
        sg_medium_release(m);
        return sg_fail(err, "%s: not a readable VDB file: truncated or corrupt (it ends before "
                       "the data it declares)", path);
    } catch (const std::exception &e) {
        sg_medium_release(m);
        return sg_fail(err, "%s: not a readable VDB file: %s", path, e.what());
    } catch (...) {
        sg_medium_release(m);
        return sg_fail(err, "%s: not a readable VDB file", path);
    }
}

extern "C" void sg_medium_release(SgMedium *m)
{
    if (!m)
        return;
    sg_grid_release(&m->grid);
    std::free(m->lights);
    m->lights = nullptr;
    m->light_count = 0;
}
