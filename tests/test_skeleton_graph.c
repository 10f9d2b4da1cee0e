/* skeleton.ply: binary round trip, ascii input, and refusal of malformed or
 * truncated files with a message that names the file. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "skeleton_graph.h"

static void temp_name(char *out, size_t cap, const char *tag)
{
    snprintf(out, cap, "/tmp/sg_test_skel_%s_%ld.ply", tag, (long)getpid());
}

static void write_bytes(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f);
    cr_assert_eq(fwrite(data, 1, size, f), size);
    fclose(f);
}

static unsigned char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc((size_t)n + 1);
    cr_assert_eq(fread(data, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return data;
}

static SgSkeleton sample_skeleton(void)
{
    SgSkeleton s = {0};
    s.node_count = 4;
    s.nodes = calloc(4, sizeof *s.nodes);
    for (uint32_t v = 0; v < 4; v++) {
        s.nodes[v].position[0] = 0.5f + (float)v;
        s.nodes[v].position[1] = -1.25f * (float)v;
        s.nodes[v].position[2] = 1e-3f;
        s.nodes[v].voxel[0] = (int)v * 3;
        s.nodes[v].voxel[1] = 7;
        s.nodes[v].voxel[2] = 100000 + (int)v;
        s.nodes[v].radius = 0.25f * (float)(v + 1);
        s.nodes[v].lifespan = (int)v * 11;
        s.nodes[v].kind = SG_NODE_PLAIN;
        s.nodes[v].light = -1;
    }
    s.nodes[1].kind = SG_NODE_LIGHT;
    s.nodes[1].light = 2;
    s.nodes[3].kind = SG_NODE_CAMERA;
    s.edge_count = 3;
    s.edges = calloc(3, sizeof *s.edges);
    for (uint32_t e = 0; e < 3; e++) {
        s.edges[e][0] = e;
        s.edges[e][1] = e + 1;
    }
    return s;
}

/* The sample skeleton written to a temporary file (temp_name(tag), its
 * path in path): the file's bytes. */
static unsigned char *written_sample(const char *tag, char path[256], size_t *size)
{
    temp_name(path, 256, tag);
    SgSkeleton a = sample_skeleton();
    SgError err = {0};
    cr_assert(sg_skeleton_write_ply(&a, path, &err), "%s", err.message);
    sg_skeleton_release(&a);
    return slurp(path, size);
}

Test(skeleton_graph, binary_round_trip_is_exact)
{
    char path[256];
    temp_name(path, sizeof path, "rt");
    SgSkeleton a = sample_skeleton(), b;
    SgError err = {0};
    cr_assert(sg_skeleton_write_ply(&a, path, &err), "%s", err.message);
    cr_assert(sg_skeleton_read_ply(&b, path, &err), "%s", err.message);
    cr_assert_eq(b.node_count, a.node_count);
    cr_assert_eq(b.edge_count, a.edge_count);
    for (uint32_t v = 0; v < a.node_count; v++) {
        for (int k = 0; k < 3; k++) {
            cr_assert_eq(b.nodes[v].position[k], a.nodes[v].position[k]);
            cr_assert_eq(b.nodes[v].voxel[k], a.nodes[v].voxel[k]);
        }
        cr_assert_eq(b.nodes[v].kind, a.nodes[v].kind);
        cr_assert_eq(b.nodes[v].radius, a.nodes[v].radius);
        cr_assert_eq(b.nodes[v].lifespan, a.nodes[v].lifespan);
        cr_assert_eq(b.nodes[v].light, a.nodes[v].light);
    }
    for (uint32_t e = 0; e < a.edge_count; e++) {
        cr_assert_eq(b.edges[e][0], a.edges[e][0]);
        cr_assert_eq(b.edges[e][1], a.edges[e][1]);
    }
    size_t size;
    unsigned char *data = slurp(path, &size);
    cr_assert(memcmp(data, "ply\nformat binary_little_endian 1.0\n", 36) == 0);
    free(data);
    unlink(path);
    sg_skeleton_release(&a);
    sg_skeleton_release(&b);
}

Test(skeleton_graph, write_refuses_bad_edge_and_leaves_no_file)
{
    char path[256];
    temp_name(path, sizeof path, "badw");
    unlink(path);
    SgSkeleton a = sample_skeleton();
    a.edges[2][1] = 9;
    SgError err = {0};
    cr_assert_not(sg_skeleton_write_ply(&a, path, &err));
    cr_assert(strstr(err.message, path) != NULL);
    cr_assert_neq(access(path, F_OK), 0);
    sg_skeleton_release(&a);
}

/* ascii, CRLF endings, an unknown element, unknown scalar and list
 * properties, no `light` property, properties in another order. */
static const char ascii_ply[] =
    "ply\r\n"
    "format ascii 1.0\r\n"
    "comment made by hand\r\n"
    "element vertex 3\r\n"
    "property float y\r\n"
    "property float x\r\n"
    "property float z\r\n"
    "property uchar red\r\n"
    "property int i\r\n"
    "property int j\r\n"
    "property int k\r\n"
    "property uchar kind\r\n"
    "property double radius\r\n"
    "property list uchar int tags\r\n"
    "property int lifespan\r\n"
    "element face 1\r\n"
    "property list uchar int vertex_indices\r\n"
    "element edge 2\r\n"
    "property int vertex1\r\n"
    "property int vertex2\r\n"
    "end_header\r\n"
    "2.5 1.5 3.5 255 1 2 3 0 0.5 2 7 8 4\r\n"
    "-1 0 0 0 4 5 6 1 1e-1 0 9\r\n"
    "0 0 1e2 12 0 0 0 2 0 1 5 0\r\n"
    "3 0 1 2\r\n"
    "0 1\r\n"
    "2 1\r\n";

Test(skeleton_graph, reads_ascii_without_light_property)
{
    SgSkeleton s;
    SgError err = {0};
    cr_assert(sg_skeleton_parse_ply(&s, ascii_ply, strlen(ascii_ply), "hand.ply", &err), "%s",
              err.message);
    cr_assert_eq(s.node_count, 3);
    cr_assert_eq(s.edge_count, 2);
    cr_assert_float_eq(s.nodes[0].position[0], 1.5f, 0);
    cr_assert_float_eq(s.nodes[0].position[1], 2.5f, 0);
    cr_assert_float_eq(s.nodes[0].position[2], 3.5f, 0);
    cr_assert_eq(s.nodes[0].voxel[2], 3);
    cr_assert_eq(s.nodes[0].lifespan, 4);
    cr_assert_float_eq(s.nodes[0].radius, 0.5f, 0);
    cr_assert_eq(s.nodes[1].kind, SG_NODE_LIGHT);
    cr_assert_eq(s.nodes[1].light, -1);
    cr_assert_eq(s.nodes[1].lifespan, 9);
    cr_assert_float_eq(s.nodes[1].radius, 0.1f, 1e-7);
    cr_assert_eq(s.nodes[2].kind, SG_NODE_CAMERA);
    cr_assert_float_eq(s.nodes[2].position[2], 100.0f, 0);
    cr_assert_eq(s.edges[1][0], 2);
    cr_assert_eq(s.edges[1][1], 1);
    sg_skeleton_release(&s);
}

static void expect_refused(const char *text, const char *why)
{
    SgSkeleton s;
    SgError err = {0};
    bool ok = sg_skeleton_parse_ply(&s, text, strlen(text), "bad.ply", &err);
    cr_assert_not(ok, "accepted: %s", why);
    cr_assert(strncmp(err.message, "bad.ply: ", 9) == 0, "message '%s' (%s)", err.message, why);
    cr_assert_eq(s.nodes, NULL);
    cr_assert_eq(s.node_count, 0);
}

#define HEAD                                                                               \
    "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"        \
    "property float z\nproperty int i\nproperty int j\nproperty int k\nproperty uchar "    \
    "kind\nproperty float radius\nproperty int lifespan\nproperty int light\n"             \
    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
#define ROW0 "0 0 0 1 1 1 0 1 0 -1\n"

/* The accepted file below (HEAD ROW0, then its second vertex row and its
 * edge) refused with field `field` of that row (0-9) set to value (-1:
 * none) and `edges` after it. */
static void expect_refused_second_row(int field, const char *value, const char *edges,
                                      const char *why)
{
    static const char *const good_row[10] = {"1", "0", "0", "2", "1", "1", "1", "1", "0", "3"};
    char text[1024];
    size_t n = (size_t)snprintf(text, sizeof text, "%s", HEAD ROW0);
    for (int f = 0; f < 10; f++) {
        const char *v = f == field ? value : good_row[f];
        n += (size_t)snprintf(text + n, sizeof text - n, "%s%s", f ? " " : "", v);
    }
    cr_assert_lt(n + strlen(edges) + 1, sizeof text);
    snprintf(text + n, sizeof text - n, "\n%s", edges);
    expect_refused(text, why);
}

Test(skeleton_graph, ascii_reference_is_valid)
{
    /* The malformed cases below differ from this accepted file by one thing. */
    const char *good = HEAD ROW0 "1 0 0 2 1 1 1 1 0 3\n0 1\n";
    SgSkeleton s;
    SgError err = {0};
    cr_assert(sg_skeleton_parse_ply(&s, good, strlen(good), "good.ply", &err), "%s",
              err.message);
    cr_assert_eq(s.nodes[1].light, 3);
    sg_skeleton_release(&s);
}

Test(skeleton_graph, refuses_malformed_ascii)
{
    expect_refused("", "empty");
    expect_refused("plx\n", "wrong magic");
    expect_refused("ply\nformat ascii 1.0\nelement vertex 1\n", "no end_header");
    expect_refused("ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n",
                   "big endian");
    expect_refused("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n",
                   "missing properties");
    expect_refused(HEAD ROW0, "truncated vertices");
    /* the edges after the good vertices */
    static const char *const edges[][2] = {{"0", "truncated edges"},
                                           {"0 2\n", "edge index out of range"},
                                           {"0 -1\n", "negative edge index"},
                                           {"1 1\n", "self loop"}};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++)
        expect_refused_second_row(-1, NULL, edges[i][0], edges[i][1]);
    /* one field of the second vertex row: x y z i j k kind radius lifespan light */
    static const struct {
        int field;
        const char *value, *why;
    } fields[] = {{0, "nan", "NaN position"},   {0, "inf", "infinite position"},
                  {7, "-1", "negative radius"}, {6, "7", "unknown kind"},
                  {6, "256", "uchar overflow"}, {9, "-2", "light below -1"},
                  {7, "1x", "garbage number"},  {3, "2.5", "float where int expected"}};
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++)
        expect_refused_second_row(fields[i].field, fields[i].value, "0 1\n", fields[i].why);
    expect_refused("ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\nproperty float "
                   "y\nproperty float z\nproperty int i\nproperty int j\nproperty int k\n"
                   "property uchar kind\nproperty float radius\nproperty int lifespan\n"
                   "end_header\n1 0 0 0 0 0 0 0 0\n",
                   "integer type for x");
    expect_refused("ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
                   "end_header\n1\n",
                   "huge count");
}

Test(skeleton_graph, refuses_every_truncation_of_a_binary_file)
{
    char path[256];
    size_t size;
    unsigned char *data = written_sample("trunc", path, &size);
    SgError err = {0};
    /* Every prefix is refused; the copy is exactly the prefix length, so
     * ASan catches any read past it. */
    for (size_t n = 0; n < size; n++) {
        unsigned char *prefix = malloc(n ? n : 1);
        memcpy(prefix, data, n);
        SgSkeleton s;
        SgError e = {0};
        cr_assert_not(sg_skeleton_parse_ply(&s, prefix, n, "cut.ply", &e), "prefix %zu", n);
        cr_assert(strncmp(e.message, "cut.ply: ", 9) == 0, "%s", e.message);
        free(prefix);
    }
    /* The file on disk, cut in the middle of the edges, through the path API. */
    write_bytes(path, data, size - 3);
    SgSkeleton s;
    err = (SgError){0};
    cr_assert_not(sg_skeleton_read_ply(&s, path, &err));
    cr_assert(strstr(err.message, path) == err.message, "%s", err.message);
    cr_assert(strstr(err.message, "truncated") != NULL, "%s", err.message);
    free(data);
    unlink(path);
}

Test(skeleton_graph, refuses_corrupted_binary_values)
{
    char path[256];
    size_t size;
    unsigned char *data = written_sample("corrupt", path, &size);
    SgError err = {0};
    size_t body = size - 4 * 37 - 3 * 8;
    /* Edge 0's second index -> 0x7fffffff. */
    unsigned char *bad = malloc(size);
    memcpy(bad, data, size);
    memcpy(bad + body + 4 * 37 + 4, "\xff\xff\xff\x7f", 4);
    SgSkeleton s;
    cr_assert_not(sg_skeleton_parse_ply(&s, bad, size, "c.ply", &err));
    cr_assert(strstr(err.message, "edge 0") != NULL, "%s", err.message);
    /* Vertex 2's x -> NaN. */
    memcpy(bad, data, size);
    memcpy(bad + body + 2 * 37, "\x00\x00\xc0\x7f", 4);
    err = (SgError){0};
    cr_assert_not(sg_skeleton_parse_ply(&s, bad, size, "c.ply", &err));
    cr_assert(strstr(err.message, "non-finite") != NULL, "%s", err.message);
    free(bad);
    free(data);
    unlink(path);
}

Test(skeleton_graph, missing_file_is_named)
{
    SgSkeleton s;
    SgError err = {0};
    cr_assert_not(sg_skeleton_read_ply(&s, "/nonexistent/dir/skeleton.ply", &err));
    cr_assert(strstr(err.message, "/nonexistent/dir/skeleton.ply: ") == err.message, "%s",
              err.message);
}
