/* Zone ids after fusions in C: each label's first pixel, the parents resolved, the labels
 * replaced (port of ../kernels/flat_zones.py's first_pixels, resolve_parents and relabel). */
#include "kernels.h"

/* A part of first_pixels' work, for a thread: the first pixel of each label in pixels
 * first .. end - 1 into ``out`` (-1 where absent); ``bad`` when a label is outside 0..count - 1. */
typedef struct {
    const int32_t *labels;
    int64_t first, end, count, *out;
    int bad;
} FirstPart;

static void *first_part(void *arg)
{
    FirstPart *p = arg;
    int64_t *out = p->out;
    for (int64_t i = 0; i < p->count; i++) {
        out[i] = -1;
    }
    for (int64_t i = p->first; i < p->end; i++) {
        int64_t label = p->labels[i];
        if (label < 0 || label >= p->count) {
            p->bad = 1;
            return NULL;
        }
        if (out[label] == -1) {
            out[label] = i;
        }
    }
    return NULL;
}

/* From BAND_MIN_PIXELS labels on (and when a part's table is small beside its pixels), in parts
 * on threads, each with its table; a label's first pixel is then that of the first part that
 * has it. */
KERNEL(first_pixels)
{
    Array labels;
    int64_t count;
    if (check_nargs("first_pixels", nargs, 2) || array_arg(args[0], NPY_INT32, 2, 0, "labels", &labels)
        || int_arg(args[1], "count", &count)) {
        return NULL;
    }
    if (count < 0) {
        PyErr_SetString(PyExc_ValueError, "first_pixels: count < 0");
        return NULL;
    }
    PyArrayObject *first = new_array_1d(count, NPY_INT64);
    if (first == NULL) {
        return NULL;
    }
    int64_t *out = PyArray_DATA(first), n = labels.size;
    int64_t n_parts = count <= n / 16 ? parts_for(n, n) : 1;
    FirstPart parts[MAX_BANDS];
    int bad = 0, failed = 0;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t k = 0; k < n_parts; k++) {
        int64_t *table = k == 0 ? out : malloc((size_t)(count > 0 ? count : 1) * sizeof(int64_t));
        parts[k] = (FirstPart){labels.data, n * k / n_parts, n * (k + 1) / n_parts, count, table};
        if (table == NULL) {
            failed = 1;
            n_parts = k;
            break;
        }
    }
    run_parts(parts, n_parts, sizeof(FirstPart), first_part);
    for (int64_t k = 0; k < n_parts; k++) {
        bad |= parts[k].bad;
    }
    for (int64_t k = 1; k < n_parts; k++) {
        if (!bad) {
            for (int64_t label = 0; label < count; label++) {
                if (out[label] == -1) {
                    out[label] = parts[k].out[label];
                }
            }
        }
        free(parts[k].out);
    }
    Py_END_ALLOW_THREADS
    if (failed) {
        Py_DECREF(first);
        return PyErr_NoMemory();
    }
    if (bad) {
        Py_DECREF(first);
        PyErr_SetString(PyExc_IndexError, "first_pixels: a label is outside 0..count - 1");
        return NULL;
    }
    return (PyObject *)first;
}

KERNEL(resolve_parents)
{
    Array parent_arg, alive_arg;
    if (check_nargs("resolve_parents", nargs, 2) || array_arg(args[0], NPY_INT32, 1, 0, "parent", &parent_arg)
        || array_arg(args[1], NPY_BOOL, 1, 0, "alive", &alive_arg)) {
        return NULL;
    }
    if (alive_arg.size < parent_arg.size || parent_arg.size == 0) {
        PyErr_SetString(PyExc_ValueError, "resolve_parents: alive is shorter than parent, or parent is empty");
        return NULL;
    }
    int32_t *parent = parent_arg.data;
    const npy_bool *alive = alive_arg.data;
    int64_t n = parent_arg.size;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t zone = 1; zone < n; zone++) {
        if (alive[zone]) {
            parent[zone] = (int32_t)zone;
        }
    }
    for (int64_t zone = 1; zone < n; zone++) {
        int64_t root = zone;
        while (root != 0 && !alive[root]) {
            root = parent[root];
        }
        int64_t walk = zone;
        while (walk != root && walk != 0 && !alive[walk]) {
            int64_t following = parent[walk];
            parent[walk] = (int32_t)root;
            walk = following;
        }
    }
    parent[0] = 0;
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

KERNEL(relabel)
{
    Array labels, lookup;
    if (check_nargs("relabel", nargs, 2) || array_arg(args[0], NPY_INT32, 1, 0, "labels", &labels)
        || array_arg(args[1], NPY_INT32, 1, 0, "lookup", &lookup)) {
        return NULL;
    }
    Py_BEGIN_ALLOW_THREADS
    relabel_in_place(labels.data, labels.size, lookup.data);
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}
