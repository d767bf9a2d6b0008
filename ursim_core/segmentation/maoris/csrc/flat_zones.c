/* MAORIS step 3 in C: flat zones, their values and sizes (port of ../kernels/flat_zones.py). */
#include "kernels.h"

/* The values computed from radii as they are labelled (label_radii_zones_counted): value =
 * table[radius - lo]; the labels are written over the radii. */
typedef struct {
    const int32_t *radii;
    int64_t lo, n_table;
    const uint8_t *table;
} ValueSource;

/* The values of ``cols`` radii from ``first``; -1 when one is outside the table. */
static int values_of(const ValueSource *source, int64_t first, int64_t cols, uint8_t *out)
{
    const int32_t *radii = source->radii + first;
    for (int64_t col = 0; col < cols; col++) {
        uint64_t index = (uint64_t)((int64_t)radii[col] - source->lo);
        if (index >= (uint64_t)source->n_table) {
            return -1;
        }
        out[col] = source->table[index];
    }
    return 0;
}

/* One band of rows of the labelling: provisional labels 1..n, numbered in the raster order of
 * the pixel that created them, with union-find parents (a set's root is always its smallest
 * label), and each label's value and pixel count. */
typedef struct {
    const uint8_t *values;
    int32_t *labels;
    int64_t cols, first_row, end_row;
    int32_t *parent;
    uint8_t *value;
    uint32_t *count; /* a band has fewer than 2^32 pixels (label_zones) */
    int64_t n, capacity;
    int failed;
    const ValueSource *source; /* or NULL: the values are read from ``values`` */
    uint8_t *rows;             /* with a source: the values of this row and the one above */
    int bad;                   /* with a source: a radius outside the table */
} LabelBand;

static int grow_band(LabelBand *b)
{
    int64_t capacity = 2 * b->capacity;
    int32_t *parent = realloc(b->parent, (size_t)capacity * sizeof(int32_t));
    if (parent == NULL) {
        return -1;
    }
    b->parent = parent;
    uint8_t *value = realloc(b->value, (size_t)capacity);
    if (value == NULL) {
        return -1;
    }
    b->value = value;
    uint32_t *count = realloc(b->count, (size_t)capacity * sizeof(uint32_t));
    if (count == NULL) {
        return -1;
    }
    b->count = count;
    b->capacity = capacity;
    return 0;
}

/* One raster pass over the band's rows; the row above the band is not looked at (the bands
 * are joined along their first rows afterwards). */
static void *label_band(void *arg)
{
    LabelBand *b = arg;
    const int64_t cols = b->cols;
    int64_t n = 0;
    uint8_t *line_values = b->rows, *above_values = b->rows + cols;
    for (int64_t row = b->first_row; row < b->end_row; row++) {
        const uint8_t *line = b->values + row * cols, *above = line - cols;
        int32_t *out = b->labels + row * cols;
        const int has_up = row > b->first_row;
        if (b->source != NULL) {
            /* The row's radii are read before its labels are written over them; the row above
             * is labels already, its values kept from the last row. */
            uint8_t *previous = line_values;
            line_values = above_values, above_values = previous;
            if (values_of(b->source, row * cols, cols, line_values) < 0) {
                b->bad = 1;
                return NULL;
            }
            line = line_values, above = above_values;
        }
        for (int64_t col = 0; col < cols; col++) {
            uint8_t value = line[col];
            if (value == 0) {
                out[col] = 0;
                continue;
            }
            int64_t left = (col > 0 && line[col - 1] == value) ? out[col - 1] : 0;
            int64_t up = (has_up && above[col] == value) ? out[col - cols] : 0;
            if (left == 0 && up == 0) {
                n += 1;
                if (n == b->capacity && grow_band(b) < 0) {
                    b->failed = 1;
                    return NULL;
                }
                b->parent[n] = (int32_t)n;
                b->value[n] = value;
                b->count[n] = 1;
                out[col] = (int32_t)n;
            } else {
                int64_t label = left != 0 ? left : up;
                out[col] = (int32_t)label;
                b->count[label] += 1;
                if (left != 0 && up != 0 && left != up) {
                    int64_t a = zone_of(left, b->parent), c = zone_of(up, b->parent);
                    if (a < c) {
                        b->parent[c] = (int32_t)a;
                    } else if (c < a) {
                        b->parent[a] = (int32_t)c;
                    }
                }
            }
        }
    }
    b->n = n;
    return NULL;
}

/* Each zone's value and size (zone 0: no value, the pixels of no zone), as
 * zone_values_and_sizes gives them; malloc'd, n_zones + 1 entries. */
typedef struct {
    int32_t *value;
    int64_t *size;
    int64_t n_zones;
} ZoneStats;

/* 4-connected components of equal non-zero value, numbered 1..N in the raster order of their
 * first pixel. Large images are labelled in bands of rows, one thread each: each band by one
 * raster pass with union-find over its own provisional labels, then the bands' labels are
 * numbered one after another (which keeps the raster order of their creation), the sets are
 * joined where equal values meet across a band's first row, and the roots (each set's smallest
 * label: the one its first pixel created) numbered in order, as one pass over the whole image
 * would. ``stats`` (or NULL): also the zones' values and sizes. ``source`` (or NULL): the
 * values come from radii through a table, and the labels are written over them (``values`` is
 * then unused). Returns 0, -1 when out of memory, or -2 when a radius is outside the table. */
static int label_zones(const uint8_t *values, int32_t *labels, int64_t rows, int64_t cols, ZoneStats *stats,
                       const ValueSource *source)
{
    int64_t pixels = rows * cols;
    int64_t n_bands = parts_for(pixels, rows);
    /* Each band's pixel counts fit in 32 bits (more bands than MAX_BANDS for images of over
     * 17 Gpx: run_parts starts them all). */
    while (n_bands < rows && ((rows + n_bands - 1) / n_bands) * cols >= (int64_t)UINT32_MAX) {
        n_bands += 1;
    }
    LabelBand *bands = calloc((size_t)n_bands, sizeof(LabelBand));
    RelabelPart *passes = calloc((size_t)n_bands, sizeof(RelabelPart));
    int64_t *offset = calloc((size_t)n_bands + 1, sizeof(int64_t));
    /* With a source, the values of the rows where the bands meet (band k's first row and the
     * one above it, at 2 * k * cols), taken before the bands write labels over them. */
    uint8_t *edges = source != NULL ? malloc((size_t)(2 * n_bands * cols + 1)) : NULL;
    int32_t *parent = NULL;
    int status = -1;
    if (bands == NULL || passes == NULL || offset == NULL || (source != NULL && edges == NULL)) {
        goto done;
    }
    for (int64_t k = 0; k < n_bands; k++) {
        LabelBand *b = bands + k;
        *b = (LabelBand){values, labels, cols, rows * k / n_bands, rows * (k + 1) / n_bands};
        b->capacity = 1024;
        b->parent = malloc((size_t)b->capacity * sizeof(int32_t));
        b->value = malloc((size_t)b->capacity);
        b->count = malloc((size_t)b->capacity * sizeof(uint32_t));
        b->source = source;
        b->rows = source != NULL ? malloc((size_t)(2 * cols + 1)) : NULL;
        if (b->parent == NULL || b->value == NULL || b->count == NULL || (source != NULL && b->rows == NULL)) {
            goto done;
        }
        if (source != NULL && k > 0
            && values_of(source, (b->first_row - 1) * cols, 2 * cols, edges + 2 * k * cols) < 0) {
            status = -2;
            goto done;
        }
    }
    run_parts(bands, n_bands, sizeof(LabelBand), label_band);
    for (int64_t k = 0; k < n_bands; k++) {
        if (bands[k].bad) {
            status = -2;
            goto done;
        }
        if (bands[k].failed) {
            goto done;
        }
        offset[k + 1] = offset[k] + bands[k].n;
    }
    int64_t total = offset[n_bands];
    if (total >= INT32_MAX) {
        goto done;
    }
    /* The bands' labels one after another (band k's label i is offset[k] + i), in the first
     * band's parents grown to hold them all rather than in a fresh array: at 8000 x 8000 px each
     * array of one entry per label is about 28 MB, and this step adds to the memory held while
     * the zone graph's is being faulted in (warm_memory). */
    parent = realloc(bands[0].parent, (size_t)(total + 1) * sizeof(int32_t));
    if (parent == NULL) {
        goto done;
    }
    bands[0].parent = NULL;
    parent[0] = 0;
    for (int64_t k = 1; k < n_bands; k++) {
        for (int64_t i = 1; i <= bands[k].n; i++) {
            parent[offset[k] + i] = (int32_t)(offset[k] + bands[k].parent[i]);
        }
        free(bands[k].parent);
        bands[k].parent = NULL;
    }
    for (int64_t k = 1; k < n_bands; k++) {
        int64_t row = bands[k].first_row;
        const uint8_t *line = source != NULL ? edges + (2 * k + 1) * cols : values + row * cols;
        const uint8_t *above = line - cols;
        const int32_t *here = labels + row * cols;
        for (int64_t col = 0; col < cols; col++) {
            if (line[col] != 0 && above[col] == line[col]) {
                int64_t a = zone_of(offset[k] + here[col], parent);
                int64_t c = zone_of(offset[k - 1] + here[col - cols], parent);
                if (a < c) {
                    parent[c] = (int32_t)a;
                } else if (c < a) {
                    parent[a] = (int32_t)c;
                }
            }
        }
    }
    /* Each label's zone, written over its parent: a label's parent is a smaller label, whose
     * entry already holds their set's zone. */
    int32_t zones = 0;
    for (int64_t label = 1; label <= total; label++) {
        parent[label] = parent[label] == label ? ++zones : parent[parent[label]];
    }
    for (int64_t k = 0; k < n_bands; k++) {
        /* Band k's labels by its own lookup, a window of the whole one: 0 stays 0. */
        passes[k] = (RelabelPart){labels, bands[k].first_row * cols, bands[k].end_row * cols, parent + offset[k], 1};
    }
    run_parts(passes, n_bands, sizeof(RelabelPart), relabel_part);
    if (stats != NULL) {
        stats->n_zones = zones;
        stats->size = calloc((size_t)zones + 1, sizeof(int64_t));
        if (stats->size == NULL) {
            goto done;
        }
        int64_t counted = 0;
        for (int64_t k = 0; k < n_bands; k++) {
            for (int64_t i = 1; i <= bands[k].n; i++) {
                stats->size[parent[offset[k] + i]] += bands[k].count[i];
                counted += bands[k].count[i];
            }
            free(bands[k].count);
            bands[k].count = NULL;
        }
        stats->size[0] = pixels - counted;
        /* The values written over the zones, in the same array: label g's zone is at most g, so
         * its entry is written after every label up to it was read. */
        for (int64_t k = 0; k < n_bands; k++) {
            for (int64_t i = 1; i <= bands[k].n; i++) {
                int64_t g = offset[k] + i;
                parent[parent[g]] = bands[k].value[i];
            }
        }
        parent[0] = 0;
        int32_t *value = realloc(parent, ((size_t)zones + 1) * sizeof(int32_t));
        stats->value = value != NULL ? value : parent;
        parent = NULL;
    }
    status = 0;
done:
    if (bands != NULL) {
        for (int64_t k = 0; k < n_bands; k++) {
            free(bands[k].parent);
            free(bands[k].value);
            free(bands[k].count);
            free(bands[k].rows);
        }
    }
    free(edges);
    free(bands);
    free(passes);
    free(offset);
    free(parent);
    return status;
}

KERNEL(label_flat_zones)
{
    Array values, labels;
    if (check_nargs("label_flat_zones", nargs, 2) || array_arg(args[0], NPY_UINT8, 2, 0, "values", &values)
        || array_arg(args[1], NPY_INT32, 2, 0, "labels", &labels)) {
        return NULL;
    }
    if (check_same_shape("label_flat_zones", "values", &values, "labels", &labels)) {
        return NULL;
    }
    int failed;
    Py_BEGIN_ALLOW_THREADS
    failed = label_zones(values.data, labels.data, values.rows, values.cols, NULL, NULL);
    Py_END_ALLOW_THREADS
    if (failed) {
        return PyErr_NoMemory();
    }
    Py_INCREF(args[1]);
    return args[1];
}

/* The (labels, value, size) of label_radii_zones_counted, from what label_zones returned. */
static PyObject *counted_result(const char *kernel, int failed, ZoneStats *stats, PyObject *labels)
{
    if (failed) {
        free(stats->value);
        free(stats->size);
        if (failed == -2) {
            PyErr_Format(PyExc_IndexError, "%s: a radius is outside lo .. lo + len(table) - 1", kernel);
            return NULL;
        }
        return PyErr_NoMemory();
    }
    npy_intp dims[1] = {stats->n_zones + 1};
    PyObject *value = array_owning(stats->value, 1, dims, NPY_INT32);
    if (value == NULL) {
        free(stats->size);
        return NULL;
    }
    PyObject *size = array_owning(stats->size, 1, dims, NPY_INT64);
    if (size == NULL) {
        Py_DECREF(value);
        return NULL;
    }
    Py_INCREF(labels);
    return Py_BuildValue("(NNN)", labels, value, size);
}

/* label_flat_zones_counted (../kernels/flat_zones.py) of the values table[radius - lo],
 * computed row by row as the rows are labelled, the labels written over the radii: no value image (64 MB of fresh memory at
 * 8000 x 8000 px, which cost more than the pass that filled it). After an IndexError the radii
 * are partly labels. */
KERNEL(label_radii_zones_counted)
{
    Array radii, table;
    int64_t lo;
    if (check_nargs("label_radii_zones_counted", nargs, 3) || array_arg(args[0], NPY_INT32, 2, 0, "radii", &radii)
        || int_arg(args[1], "lo", &lo) || array_arg(args[2], NPY_UINT8, 1, 0, "table", &table)) {
        return NULL;
    }
    ValueSource source = {radii.data, lo, table.size, table.data};
    ZoneStats stats = {NULL, NULL, 0};
    int failed;
    Py_BEGIN_ALLOW_THREADS
    failed = label_zones(NULL, radii.data, radii.rows, radii.cols, &stats, &source);
    Py_END_ALLOW_THREADS
    return counted_result("label_radii_zones_counted", failed, &stats, args[0]);
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
