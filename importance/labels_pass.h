/* The propagation's passes for one key width, included by labels.c with
 * KEY_T (uint32_t or uint64_t) and PASS(name) (name with a width suffix)
 * defined. A key is distance << L->shift | node; a node field of all ones
 * is "no node". Internal to labels.c. */

/* Dijkstra inside one slab from its seeds (sorted by distance, fed into the
 * ring as the distance reaches them). */
static void PASS(run_slab)(void *ctx, uint64_t index, int thread)
{
    (void)thread;
    Labeller *L = ctx;
    Slab *s = &L->slabs[index];
    KEY_T *key = L->key;
    const int shift = L->shift;
    const uint64_t node_mask = L->node_mask;
    if (s->seeds.count == 0)
        return;
    qsort(s->seeds.items, s->seeds.count, sizeof *s->seeds.items, compare_u64);
    size_t next_seed = 0, pending = 0;
    uint32_t d = (uint32_t)(s->seeds.items[0] >> 32);
    for (;;) {
        while (next_seed < s->seeds.count && (uint32_t)(s->seeds.items[next_seed] >> 32) == d) {
            if (!buffer_push(&s->ring[d % RING], (uint32_t)s->seeds.items[next_seed]))
                s->failed = true;
            next_seed++;
            pending++;
        }
        if (pending == 0) {
            if (next_seed == s->seeds.count)
                break;
            d = (uint32_t)(s->seeds.items[next_seed] >> 32);
            continue;
        }
        Buffer *b = &s->ring[d % RING];
        for (size_t q = 0; q < b->count; q++) {
            uint32_t v = (uint32_t)b->items[q];
            uint64_t k = key[v];
            if ((k >> shift) != d)
                continue; /* superseded by a shorter path */
            s->relaxed++;
            uint64_t label = k & node_mask;
            for (int e = 0; e < 26; e++) {
                size_t u = (size_t)((long)v + L->off[e]);
                if (u < s->lo || u >= s->hi)
                    continue; /* the neighbouring slab's: exchanged later */
                uint32_t nd = d + L->weight[e];
                uint64_t want = (uint64_t)nd << shift | label;
                uint64_t cur = key[u];
                if (want < cur) {
                    if (nd > L->distance_limit) {
                        s->overflow = true; /* the caller retries with 64-bit keys */
                        continue;
                    }
                    key[u] = (KEY_T)want;
                    /* In the first round every reached voxel was queued at
                     * its distance when it got it: a lower node at the same
                     * distance needs no new entry. Later rounds start from
                     * keys set before, so any change is queued. */
                    if ((cur >> shift) > nd || !L->first_round) {
                        if (!buffer_push(&s->ring[nd % RING], u))
                            s->failed = true;
                        pending++;
                    }
                }
            }
        }
        pending -= b->count;
        b->count = 0;
        d++;
    }
    s->seeds.count = 0;
}

/* Relaxes plane `from` into the adjacent plane `to` (z differs by one),
 * seeding `slab` with every voxel that improved. */
static bool PASS(exchange)(Labeller *L, size_t from, size_t to, Slab *slab, size_t px)
{
    KEY_T *key = L->key;
    const int shift = L->shift;
    const uint64_t node_mask = L->node_mask;
    long dz = to > from ? (long)L->plane : -(long)L->plane;
    bool ok = true;
    for (size_t v = from; v < from + L->plane; v++) {
        uint64_t k = key[v];
        if ((k & node_mask) == node_mask)
            continue; /* blocked or not reached */
        uint32_t d = (uint32_t)(k >> shift);
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                long o = dz + dx + (long)px * dy;
                size_t u = (size_t)((long)v + o);
                if (u < to || u >= to + L->plane)
                    continue;
                uint32_t nd = d + (dx == 0 && dy == 0 ? W_FACE : dx == 0 || dy == 0 ? W_EDGE
                                                                                    : W_CORNER);
                uint64_t want = (uint64_t)nd << shift | (k & node_mask);
                if (want < key[u]) {
                    if (nd > L->distance_limit) {
                        slab->overflow = true;
                        continue;
                    }
                    key[u] = (KEY_T)want;
                    ok = ok && buffer_push(&slab->seeds, (uint64_t)nd << 32 | u);
                }
            }
    }
    return ok;
}

/* Blocked cells everywhere, unseen on the medium; counts medium per plane. */
static void PASS(fill)(Labeller *L, const SgGrid *grid, size_t px, size_t py, size_t total,
                       uint64_t *plane_medium)
{
    KEY_T *key = L->key;
    const KEY_T blocked = (KEY_T)L->node_mask, unseen = (KEY_T)~(KEY_T)0;
    for (size_t v = 0; v < total; v++)
        key[v] = blocked;
    for (int k = 0; k < grid->nz; k++)
        for (int j = 0; j < grid->ny; j++) {
            const uint8_t *row = grid->voxels + sg_grid_index(grid, 0, j, k);
            KEY_T *krow = key + 1 + px * ((size_t)(j + 1) + py * (size_t)(k + 1));
            for (int i = 0; i < grid->nx; i++)
                if (row[i]) {
                    krow[i] = unseen;
                    plane_medium[k + 1]++;
                }
        }
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

static uint64_t PASS(count_labelled)(const Labeller *L, size_t total)
{
    const KEY_T *key = L->key;
    uint64_t labelled = 0;
    for (size_t v = 0; v < total; v++)
        labelled += (key[v] & L->node_mask) != L->node_mask;
    return labelled;
}
