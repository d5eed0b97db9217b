/*
 * Skin a model exported by cgaskin with the generated C99 headers, and check it against cgaskin.
 *
 *   python examples/c_skinning/export.py Fox.glb fox.bin --clip Run --time 0.37 --headers build
 *   cc -std=c99 -Wall -Wextra -Werror -O2 -ffp-contract=off -Ibuild \
 *      examples/c_skinning/skin_model.c -o skin_model -lm
 *   ./skin_model fox.bin [skinned.bin]
 *
 * The file layout is export.py's. Per frame an engine would do what main() does once: per bone
 * cgaskin_bone_affines (or take 3x4 maps it already has), then cgaskin_skin_blend over the vertices.
 * Exit status 0 when both stages equal cgaskin within 1e-12 of the model's size and the blend found no
 * bad input.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cgaskin_skin.h"

static void *read_array(FILE *f, size_t count, size_t size)
{
    void *p = malloc(count * size > 0 ? count * size : 1);
    if (p == NULL || fread(p, size, count, f) != count) {
        fprintf(stderr, "truncated file or out of memory\n");
        exit(2);
    }
    return p;
}

static double max_abs_diff(const double *a, const double *b, size_t count, double *size)
{
    double worst = 0.0;
    size_t i;
    *size = 0.0;
    for (i = 0; i < count; ++i) {
        const double d = fabs(a[i] - b[i]);
        worst = d > worst ? d : worst;
        *size = fabs(b[i]) > *size ? fabs(b[i]) : *size;
    }
    return worst;
}

int main(int argc, char **argv)
{
    char magic[8];
    uint64_t counts[4];
    size_t n, k, n_bones, n_versors, i;
    double *rest, *weights, *affines, *expected, *versors, *versor_affines, *out, *affines_c;
    int32_t *joints;
    double size, err, aff_size, aff_err, checksum = 0.0;
    cgaskin_skin_counts bad;
    FILE *f;

    if (argc < 2) {
        fprintf(stderr, "usage: %s model.bin [skinned.bin]\n", argv[0]);
        return 2;
    }
    f = fopen(argv[1], "rb");
    if (f == NULL || fread(magic, 1, 8, f) != 8 || memcmp(magic, "CGASKIN1", 8) != 0
            || fread(counts, sizeof counts[0], 4, f) != 4) {
        fprintf(stderr, "%s is not a file written by examples/c_skinning/export.py\n", argv[1]);
        return 2;
    }
    n = (size_t)counts[0];
    k = (size_t)counts[1];
    n_bones = (size_t)counts[2];
    n_versors = (size_t)counts[3];
    rest = read_array(f, 3 * n, sizeof(double));
    joints = read_array(f, k * n, sizeof(int32_t));
    weights = read_array(f, k * n, sizeof(double));
    affines = read_array(f, 12 * n_bones, sizeof(double));
    expected = read_array(f, 3 * n, sizeof(double));
    versors = read_array(f, 12 * n_versors, sizeof(double));
    versor_affines = read_array(f, 12 * n_versors, sizeof(double));
    fclose(f);
    out = malloc(3 * n * sizeof(double) + 1);
    affines_c = malloc(12 * n_versors * sizeof(double) + 1);
    if (out == NULL || affines_c == NULL)
        return 2;

    /* stage 1, per bone: versor -> 3x4 affine map */
    cgaskin_bone_affines(n_versors, versors, affines_c);
    aff_err = max_abs_diff(affines_c, versor_affines, 12 * n_versors, &aff_size);
    /* stage 2, per vertex: blend the bones' maps by the weights, apply once */
    bad = cgaskin_skin_blend(n, k, rest, joints, weights, n_bones, affines, out);
    err = max_abs_diff(out, expected, 3 * n, &size);
    for (i = 0; i < 3 * n; ++i)
        checksum += out[i];

    printf("vertices %lu x %lu influences, %lu bones\n", (unsigned long)n, (unsigned long)k, (unsigned long)n_bones);
    printf("bone_affines: %lu versors, max |C - cgaskin| = %.3e (relative %.3e)\n", (unsigned long)n_versors,
           aff_err, aff_err / (aff_size > 1.0 ? aff_size : 1.0));
    printf("skin_blend: max |C - cgaskin.skin| = %.3e (relative to the model's size %.3e: %.3e)\n",
           err, size, err / (size > 1.0 ? size : 1.0));
    printf("bad joints %lu, bad weights %lu, non-finite %lu\n", (unsigned long)bad.bad_joints,
           (unsigned long)bad.bad_weights, (unsigned long)bad.bad_values);
    printf("checksum %.17g\n", checksum);
    if (argc > 2) {
        FILE *o = fopen(argv[2], "wb");
        if (o == NULL || fwrite(out, sizeof(double), 3 * n, o) != 3 * n)
            return 2;
        fclose(o);
    }
    return (bad.bad_joints || bad.bad_weights || bad.bad_values
            || err > 1e-12 * (size > 1.0 ? size : 1.0) || aff_err > 1e-12 * (aff_size > 1.0 ? aff_size : 1.0));
}
