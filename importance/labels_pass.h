/* The propagation's passes for one key width, included by labels.c with
 * KEY_T (uint32_t or uint64_t) and PASS(name) (name with a width suffix)
 * defined. A key is distance << L->shift | node; a node field of all ones
 * is "no node". Internal to labels.c. */

/* Copies tile t and its halo into the thread's local copy (local (x, y, z)
 * is padded voxel origin + (x, y, z)) and gathers its seeds, the voxels
 * its bitmap marks, as distance << 16 | local index, in order. */
static void PASS(copy_in)(Labeller *L, Tile *t, Workspace *w, size_t origin)
{
    const KEY_T *key = L->key;
    KEY_T *local = w->local;
    uint32_t *changed = L->changed + (size_t)(t - L->tiles) * TILE * TILE;
    for (int z = 0; z < t->ez + 2; z++)
        for (int y = 0; y < t->ey + 2; y++)
            memcpy(local + TL * (y + TL * z), key + origin + L->px * (size_t)y + L->plane * (size_t)z,
                   (size_t)(t->ex + 2) * sizeof *local);
    w->seeds.count = 0;
    for (int r = 0; r < TILE * TILE; r++) {
        uint32_t bits = changed[r];
        changed[r] = 0;
        while (bits) {
            int x = __builtin_ctz(bits);
            bits &= bits - 1;
            unsigned v = (unsigned)(x + 1 + TL * (r % TILE + 1 + TL * (r / TILE + 1)));
            if (!buffer_push(&w->seeds, (uint64_t)(local[v] >> L->shift) << 16 | v))
                w->failed = true;
        }
    }
    qsort(w->seeds.items, w->seeds.count, sizeof(uint64_t), compare_u64);
}

/* Relaxes the 26 neighbours of local voxel v, settled at distance d;
 * returns how many it queued. */
static size_t PASS(relax)(Labeller *L, const Tile *t, Workspace *w, unsigned v, uint32_t d, bool ran)
{
    KEY_T *local = w->local;
    const int shift = L->shift;
    const int ex = t->ex, ey = t->ey, ez = t->ez;
    uint64_t label = local[v] & L->node_mask;
    unsigned x = v % TL, y = v / TL % TL, z = v / (TL * TL);
    size_t queued = 0;
    /* next to the halo: some neighbours are other tiles' */
    bool edge = x == 1 || y == 1 || z == 1 || x == (unsigned)ex || y == (unsigned)ey || z == (unsigned)ez;
    for (int e = 0; e < 26; e++) {
        unsigned u = (unsigned)((int)v + L->local_off[e]);
        uint32_t nd = d + L->weight[e];
        uint64_t want = (uint64_t)nd << shift | label;
        uint64_t cur = local[u];
        if (want >= cur)
            continue;
        if (nd > L->distance_limit) {
            w->overflow = true; /* the caller retries with 64-bit keys */
            continue;
        }
        local[u] = (KEY_T)want;
        if (edge) {
            unsigned ux = u % TL, uy = u / TL % TL, uz = u / (TL * TL);
            if (ux == 0 || uy == 0 || uz == 0 || ux == (unsigned)ex + 1 || uy == (unsigned)ey + 1 ||
                uz == (unsigned)ez + 1)
                continue; /* the halo: sent after the run */
        }
        /* In a tile's first run every voxel with a key was a seed, queued
         * at its distance, and every voxel reached since was queued when
         * it got its distance: a lower node at the same distance needs no
         * new entry. Later runs start from keys settled before, so any
         * change is queued. */
        if ((cur >> shift) > nd || ran) {
            if (!ring_push(&w->ring[nd % RING], (uint16_t)u))
                w->failed = true;
            queued++;
        }
    }
    return queued;
}

/* Dijkstra on the local copy from its seeds, fed into the ring of buckets
 * as the distance reaches them. */
static void PASS(propagate)(Labeller *L, const Tile *t, Workspace *w, bool ran)
{
    const KEY_T *local = w->local;
    const uint64_t *seeds = w->seeds.items;
    const size_t seed_count = w->seeds.count;
    size_t next_seed = 0, pending = 0;
    uint32_t d = seed_count ? (uint32_t)(seeds[0] >> 16) : 0;
    while (seed_count) {
        while (next_seed < seed_count && (uint32_t)(seeds[next_seed] >> 16) == d) {
            if (!ring_push(&w->ring[d % RING], (uint16_t)seeds[next_seed]))
                w->failed = true;
            next_seed++;
            pending++;
        }
        if (pending == 0) {
            if (next_seed == seed_count)
                break;
            d = (uint32_t)(seeds[next_seed] >> 16);
            continue;
        }
        Ring *b = &w->ring[d % RING];
        for (size_t q = 0; q < b->count; q++) {
            unsigned v = b->items[q];
            if ((local[v] >> L->shift) != d)
                continue; /* superseded by a shorter path */
            w->relaxed++;
            pending += PASS(relax)(L, t, w, v, d, ran);
        }
        pending -= b->count;
        b->count = 0;
        d++;
    }
}

/* Copies the tile's own voxels back, and sends the halo's improvements to
 * the thread's outbox, once each (its keys do not change during the
 * phase: the tiles around are not running). */
static void PASS(copy_out)(Labeller *L, Tile *t, Workspace *w, int thread, size_t origin)
{
    KEY_T *key = L->key;
    const KEY_T *local = w->local;
    const size_t px = L->px, plane = L->plane;
    const int ex = t->ex, ey = t->ey, ez = t->ez;
    for (int z = 1; z <= ez; z++)
        for (int y = 1; y <= ey; y++)
            memcpy(key + origin + 1 + px * (size_t)y + plane * (size_t)z, local + 1 + TL * (y + TL * z),
                   (size_t)ex * sizeof *local);
    t->out_thread = thread;
    t->out_begin = w->outbox.count;
    for (int z = 0; z < ez + 2; z++)
        for (int y = 0; y < ey + 2; y++) {
            bool face = z == 0 || z == ez + 1 || y == 0 || y == ey + 1;
            for (int x = 0; x < ex + 2; x += face || x == ex + 1 ? 1 : ex + 1) {
                unsigned u = (unsigned)(x + TL * (y + TL * z));
                size_t g = origin + (size_t)x + px * (size_t)y + plane * (size_t)z;
                if (local[u] < key[g] && !OUTBOX_PUSH(&w->outbox, g, local[u]))
                    w->failed = true;
            }
        }
    t->out_end = w->outbox.count;
}

/* Dijkstra inside one tile, on a copy of the tile and its one-voxel halo:
 * the copy stays in the core's cache where the whole key array does not.
 * Its seeds are its voxels whose keys changed since its last run (marked
 * in its bitmap), fed into the ring as the distance reaches them. Keys
 * that improve in the halo belong to neighbouring tiles: after the run
 * they go to the thread's outbox, applied after the phase. Only the
 * tile's own voxels are copied back. */
static void PASS(run_tile)(void *ctx, uint64_t index, int thread)
{
    Labeller *L = ctx;
    Tile *t = L->phase[index];
    Workspace *w = &L->work[thread];
    const size_t origin = (size_t)t->x0 + L->px * ((size_t)t->y0 + L->py * (size_t)t->z0);
    PASS(copy_in)(L, t, w, origin);
    t->dirty = false;
    const bool ran = t->ran;
    PASS(propagate)(L, t, w, ran);
    PASS(copy_out)(L, t, w, thread, origin);
    t->ran = true;
}

/* Applies a phase's outboxes, in tile order: a key that improves marks its
 * voxel in its tile's bitmap. The keys after this do not depend on the
 * order (each is a minimum), nor do the marks. */
static void PASS(apply)(Labeller *L, size_t tiles)
{
    KEY_T *key = L->key;
    for (size_t i = 0; i < tiles; i++) {
        const Tile *t = L->phase[i];
        const Buffer *out = &L->work[t->out_thread].outbox;
        for (size_t j = t->out_begin; j < t->out_end; j += OUTBOX_WORDS) {
            size_t g;
            uint64_t want;
            OUTBOX_READ(out->items + j, g, want);
            if (want < key[g]) {
                key[g] = (KEY_T)want;
                mark_changed(L, g);
            }
        }
    }
    for (int t = 0; t < L->threads; t++)
        L->work[t].outbox.count = 0;
}

/* Padded z plane k: blocked cells everywhere, unseen on the medium;
 * counts its medium (a plane per task). */
static void PASS(fill_plane)(void *ctx, uint64_t k, int thread)
{
    (void)thread;
    PlaneJob *job = ctx;
    const Labeller *L = job->L;
    const SgGrid *grid = job->grid;
    KEY_T *plane = (KEY_T *)L->key + L->plane * k;
    const KEY_T blocked = (KEY_T)L->node_mask, unseen = (KEY_T)~(KEY_T)0;
    uint64_t medium = 0;
    for (size_t v = 0; v < L->plane; v++)
        plane[v] = blocked;
    for (int j = 0; k >= 1 && k <= (uint64_t)grid->nz && j < grid->ny; j++) {
        const uint8_t *row = grid->voxels + sg_grid_index(grid, 0, j, (int)k - 1);
        KEY_T *krow = plane + 1 + L->px * (size_t)(j + 1);
        for (int i = 0; i < grid->nx; i++)
            if (row[i]) {
                krow[i] = unseen;
                medium++;
            }
    }
    job->count[k] = medium;
}

/* Padded z plane k: its voxels with a node. */
static void PASS(count_plane)(void *ctx, uint64_t k, int thread)
{
    (void)thread;
    PlaneJob *job = ctx;
    const Labeller *L = job->L;
    const KEY_T *plane = (const KEY_T *)L->key + L->plane * k;
    uint64_t labelled = 0;
    for (size_t v = 0; v < L->plane; v++)
        labelled += (plane[v] & L->node_mask) != L->node_mask;
    job->count[k] = labelled;
}

/* Seeds voxel v with node s unless a lower node stands there already. */
static bool PASS(seed)(Labeller *L, size_t v, uint32_t s)
{
    KEY_T *key = L->key;
    if (key[v] != (KEY_T)~(KEY_T)0)
        return false;
    key[v] = (KEY_T)s;
    return true;
}

