/* MAORIS step 3 in C: flat zones, zone values and sizes, relabelling (port of ../kernels/flat_zones.py). */
#include "kernels.h"

/* 4-connected components of equal non-zero value, numbered 1..N in the raster order of their
 * first pixel, by one raster pass with union-find over provisional labels (a set's root is
 * always its smallest label). Returns 0, or -1 when out of memory. */
static int label_zones(const uint8_t *restrict values, int32_t *restrict labels, int64_t rows, int64_t cols)
{
    int64_t capacity = 1024, n = 0;
    int32_t *parent = malloc((size_t)capacity * sizeof(int32_t));
    if (parent == NULL) {
        return -1;
    }
    for (int64_t row = 0; row < rows; row++) {
        const uint8_t *line = values + row * cols;
        int32_t *out = labels + row * cols;
        for (int64_t col = 0; col < cols; col++) {
            uint8_t value = line[col];
            if (value == 0) {
                out[col] = 0;
                continue;
            }
            int64_t left = (col > 0 && line[col - 1] == value) ? out[col - 1] : 0;
            int64_t up = (row > 0 && line[col - cols] == value) ? out[col - cols] : 0;
            if (left == 0 && up == 0) {
                n += 1;
                if (n == capacity) {
                    int32_t *grown = realloc(parent, (size_t)(2 * n) * sizeof(int32_t));
                    if (grown == NULL) {
                        free(parent);
                        return -1;
                    }
                    parent = grown;
                    capacity = 2 * n;
                }
                parent[n] = (int32_t)n;
                out[col] = (int32_t)n;
            } else {
                out[col] = (int32_t)(left != 0 ? left : up);
                if (left != 0 && up != 0) {
                    int64_t a = zone_of(left, parent), b = zone_of(up, parent);
                    if (a < b) {
                        parent[b] = (int32_t)a;
                    } else if (b < a) {
                        parent[a] = (int32_t)b;
                    }
                }
            }
        }
    }
    int32_t *final = calloc((size_t)(n + 1), sizeof(int32_t));
    if (final == NULL) {
        free(parent);
        return -1;
    }
    int32_t zones = 0;
    for (int64_t label = 1; label <= n; label++) {
        int64_t root = zone_of(label, parent);
        if (root == label) {
            final[label] = ++zones;
        } else {
            final[label] = final[root];
        }
    }
    relabel_in_place(labels, rows * cols, final);
    free(final);
    free(parent);
    return 0;
}

KERNEL(label_flat_zones)
{
    Array values, labels;
    if (check_nargs("label_flat_zones", nargs, 2) || array_arg(args[0], NPY_UINT8, 2, 0, "values", &values)
        || array_arg(args[1], NPY_INT32, 2, 0, "labels", &labels)) {
        return NULL;
    }
    if (labels.rows != values.rows || labels.cols != values.cols) {
        PyErr_SetString(PyExc_ValueError, "label_flat_zones: values and labels differ in shape");
        return NULL;
    }
    int failed;
    Py_BEGIN_ALLOW_THREADS
    failed = label_zones(values.data, labels.data, values.rows, values.cols);
    Py_END_ALLOW_THREADS
    if (failed) {
        return PyErr_NoMemory();
    }
    Py_INCREF(args[1]);
    return args[1];
}

KERNEL(zone_values_and_sizes)
{
    Array zones, values;
    int64_t count;
    if (check_nargs("zone_values_and_sizes", nargs, 3) || array_arg(args[0], NPY_INT32, 2, 0, "zones", &zones)
        || array_arg(args[1], NPY_UINT8, 2, 0, "values", &values) || int_arg(args[2], "count", &count)) {
        return NULL;
    }
    if (zones.rows != values.rows || zones.cols != values.cols || count < 0) {
        PyErr_SetString(PyExc_ValueError, "zone_values_and_sizes: zones and values differ in shape, or count < 0");
        return NULL;
    }
    PyArrayObject *value = new_array_1d(count, NPY_INT32), *size = new_array_1d(count, NPY_INT64);
    if (value == NULL || size == NULL) {
        Py_XDECREF(value);
        Py_XDECREF(size);
        return NULL;
    }
    int32_t *out_value = PyArray_DATA(value);
    int64_t *out_size = PyArray_DATA(size);
    const int32_t *zone = zones.data;
    const uint8_t *pixel_value = values.data;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    memset(out_value, 0, (size_t)count * sizeof(int32_t));
    memset(out_size, 0, (size_t)count * sizeof(int64_t));
    for (int64_t i = 0; i < zones.size; i++) {
        int64_t z = zone[i];
        if (z < 0 || z >= count) {
            bad = 1;
            break;
        }
        out_value[z] = pixel_value[i];
        out_size[z] += 1;
    }
    Py_END_ALLOW_THREADS
    if (bad) {
        Py_DECREF(value);
        Py_DECREF(size);
        PyErr_SetString(PyExc_IndexError, "zone_values_and_sizes: a zone label is outside 0..count - 1");
        return NULL;
    }
    return Py_BuildValue("(NN)", value, size);
}

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
    int64_t *out = PyArray_DATA(first);
    const int32_t *flat = labels.data;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < count; i++) {
        out[i] = -1;
    }
    for (int64_t i = 0; i < labels.size; i++) {
        int64_t label = flat[i];
        if (label < 0 || label >= count) {
            bad = 1;
            break;
        }
        if (out[label] == -1) {
            out[label] = i;
        }
    }
    Py_END_ALLOW_THREADS
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
