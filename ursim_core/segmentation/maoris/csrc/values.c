/* MAORIS step 2 in C: the radii mapped to the value image through a table (port of
 * ../kernels/discs.py's lookup_bytes). */
#include "kernels.h"

/* A part of the image, for a thread: out[i] = table[values[i] - lo]; ``bad`` when a value is
 * outside the table. */
typedef struct {
    const int32_t *values;
    uint8_t *out;
    int64_t first, end, lo, n_table;
    const uint8_t *table;
    int bad;
} LookupPart;

static void *lookup_part(void *arg)
{
    LookupPart *p = arg;
    const int32_t *values = p->values;
    uint8_t *out = p->out;
    const uint8_t *table = p->table;
    uint64_t n_table = (uint64_t)p->n_table;
    int64_t lo = p->lo;
    for (int64_t i = p->first; i < p->end; i++) {
        uint64_t index = (uint64_t)((int64_t)values[i] - lo);
        if (index >= n_table) {
            p->bad = 1;
            return NULL;
        }
        out[i] = table[index];
    }
    return NULL;
}

/* Large images in parts, one thread each: the output is fresh memory (64 MB at 8000 x 8000 px),
 * whose first touch costs as much as the pass itself on the virtual machines measured. */
KERNEL(lookup_bytes)
{
    Array values, table, out;
    int64_t lo;
    if (check_nargs("lookup_bytes", nargs, 4) || array_arg(args[0], NPY_INT32, 2, 0, "values", &values)
        || int_arg(args[1], "lo", &lo) || array_arg(args[2], NPY_UINT8, 1, 0, "table", &table)
        || array_arg(args[3], NPY_UINT8, 2, 0, "out", &out)) {
        return NULL;
    }
    if (check_same_shape("lookup_bytes", "values", &values, "out", &out)) {
        return NULL;
    }
    int64_t n = values.size;
    int64_t n_parts = parts_for(n, n);
    LookupPart parts[MAX_BANDS];
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t k = 0; k < n_parts; k++) {
        parts[k] = (LookupPart){values.data, out.data, n * k / n_parts, n * (k + 1) / n_parts, lo, table.size,
                                table.data};
    }
    run_parts(parts, n_parts, sizeof(LookupPart), lookup_part);
    for (int64_t k = 0; k < n_parts; k++) {
        bad |= parts[k].bad;
    }
    Py_END_ALLOW_THREADS
    if (bad) {
        PyErr_SetString(PyExc_IndexError, "lookup_bytes: a value is outside lo .. lo + len(table) - 1");
        return NULL;
    }
    Py_RETURN_NONE;
}
