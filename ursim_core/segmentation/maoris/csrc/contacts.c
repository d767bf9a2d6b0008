/* Counting the contacts of a MAORIS label image in C (port of ../kernels/contacts.py, whose
 * docstrings explain the method): compacting the labels, counting every contact of a band of
 * pixels, joining the counts of two bands, linking the border candidates per zone, and the
 * table of all counts. The storage is contact_table.h, the pixel rules contact_rules.h.
 *
 * count_contacts runs without the GIL: contact_tracking.start_tracking counts the bands of a
 * large image on threads at the same time. */
#include "contact_rules.h"
#include "contact_table.h"
#include "kernels.h"

/* Size of the cache of pending counts when counting from scratch (count_contacts). */
#define PENDING_BITS 14

/* What _counted returns: the border candidates (``used`` of ``capacity`` written), the table,
 * the per-zone slots and the contour sizes; every array malloc'd. */
typedef struct {
    int32_t *pixels;
    int64_t capacity, used;
    Table table;
    int64_t *slots, *total;
} Counts;

static void counts_release(Counts *counts)
{
    free(counts->pixels);
    table_release(&counts->table);
    free(counts->table.meta);
    free(counts->slots);
    free(counts->total);
    memset(counts, 0, sizeof(*counts));
}

/* _counted: the contact counts of the pixels start..stop - 1 of a compact, padded, flattened
 * label image of n zones (every label its own zone). Returns 0, or -1 when out of memory
 * (nothing left allocated). The pixels outside the range are only read. */
static int counted(const int32_t *labels, int64_t width, int64_t n, int64_t start, int64_t stop, Counts *out)
{
    memset(out, 0, sizeof(*out));
    /* Room for every pixel of the range: pages never written are never faulted in. */
    out->capacity = stop - start > 1 ? stop - start : 1;
    out->pixels = malloc((size_t)out->capacity * sizeof(int32_t));
    out->slots = filled_i64(n * SLOTS, -1);
    out->total = calloc((size_t)(n > 0 ? n : 1), sizeof(int64_t));
    int64_t *pending_keys = filled_i64((int64_t)1 << PENDING_BITS, EMPTY);
    int64_t *pending_counts = calloc((size_t)1 << PENDING_BITS, sizeof(int64_t));
    if (out->pixels == NULL || out->slots == NULL || out->total == NULL || pending_keys == NULL
        || pending_counts == NULL || table_new(16, &out->table) < 0) {
        goto fail;
    }
    for (int64_t zone = 0; zone < n; zone++) {
        out->slots[zone * SLOTS] = 0;
    }
    Table *table = &out->table;
    int32_t around[9], partners[9];
    int64_t base = n, n_candidates = 0;
    for (int64_t pixel = start; pixel < stop; pixel++) {
        int32_t zone = labels[pixel];
        if (zone == 0 || same_labels_around(labels, pixel, width)) {
            continue;
        }
        out->pixels[n_candidates++] = (int32_t)pixel;
        raw_neighbourhood(labels, pixel, width, around);
        int64_t own = around[4];
        int64_t count = count_pixel(around, partners, out->total);
        for (int64_t i = 0; i < count; i++) {
            /* A boundary repeats its pair on every pixel, while the zones' counts are far
             * apart in memory: the counts are gathered in a small cache of pairs first. */
            int64_t key = own * base + partners[i];
            int64_t index = (int64_t)(((uint64_t)key * GOLDEN) >> (64 - PENDING_BITS));
            if (pending_keys[index] == key) {
                pending_counts[index] += 1;
                continue;
            }
            if (pending_keys[index] != EMPTY) {
                if (2 * (table->meta[0] + 1) > table->size && table_reserve(table, 1) < 0) {
                    goto fail;
                }
                int64_t evicted = pending_keys[index];
                contact_add(out->slots, table, base, evicted / base, evicted % base, pending_counts[index], NULL);
            }
            pending_keys[index] = key;
            pending_counts[index] = 1;
        }
    }
    if (table_reserve(table, (int64_t)1 << PENDING_BITS) < 0) {
        goto fail;
    }
    for (int64_t index = 0; index < ((int64_t)1 << PENDING_BITS); index++) {
        if (pending_keys[index] != EMPTY) {
            int64_t key = pending_keys[index];
            contact_add(out->slots, table, base, key / base, key % base, pending_counts[index], NULL);
        }
    }
    out->used = n_candidates;
    free(pending_keys);
    free(pending_counts);
    return 0;
fail:
    free(pending_keys);
    free(pending_counts);
    counts_release(out);
    return -1;
}

/* The tuple count_contacts returns, (pixels, used, keys, counts, meta, slots, total), made of
 * the arrays of ``counts`` (which it then owns, also on failure). */
static PyObject *counts_tuple(Counts *counts, int64_t n)
{
    npy_intp dims_pixels[1] = {counts->capacity}, dims_table[1] = {counts->table.size};
    npy_intp dims_meta[1] = {META_SIZE}, dims_slots[1] = {n * SLOTS}, dims_total[1] = {n};
    PyObject *items[6] = {NULL};
    items[0] = array_owning(counts->pixels, 1, dims_pixels, NPY_INT32);
    items[1] = array_owning(counts->table.keys, 1, dims_table, NPY_INT64);
    items[2] = array_owning(counts->table.counts, 1, dims_table, NPY_INT64);
    items[3] = array_owning(counts->table.meta, 1, dims_meta, NPY_INT64);
    items[4] = array_owning(counts->slots, 1, dims_slots, NPY_INT64);
    items[5] = array_owning(counts->total, 1, dims_total, NPY_INT64);
    int64_t used = counts->used;
    memset(counts, 0, sizeof(*counts));
    PyObject *result = NULL;
    if (items[0] && items[1] && items[2] && items[3] && items[4] && items[5]) {
        result = Py_BuildValue("(OLOOOOO)", items[0], (long long)used, items[1], items[2], items[3], items[4], items[5]);
    }
    for (int k = 0; k < 6; k++) {
        Py_XDECREF(items[k]);
    }
    return result;
}

/* Renumber the live zones 1..n - 1 in id order: compact_of (0 for dead ids) and the original
 * ids (original[k - 1] of compact zone k, ``count`` of them). */
static void compact_ids(const npy_bool *alive, int64_t n_alive, int32_t *original, int32_t *compact_of)
{
    int64_t k = 0;
    for (int64_t id = 0; id < n_alive; id++) {
        compact_of[id] = 0;
        if (alive[id]) {
            original[k] = (int32_t)id;
            compact_of[id] = (int32_t)(k + 1);
            k += 1;
        }
    }
}

static int64_t count_alive(const npy_bool *alive, int64_t n_alive)
{
    int64_t count = 0;
    for (int64_t id = 0; id < n_alive; id++) {
        count += alive[id] != 0;
    }
    return count;
}

KERNEL(_compact_labels)
{
    Array labels, alive;
    if (check_nargs("_compact_labels", nargs, 2) || array_arg(args[0], NPY_INT32, 1, 0, "labels", &labels)
        || array_arg(args[1], NPY_BOOL, 1, 0, "alive", &alive)) {
        return NULL;
    }
    int64_t live = count_alive(alive.data, alive.size);
    PyArrayObject *original = new_array_1d(live, NPY_INT32), *compact_of = new_array_1d(alive.size, NPY_INT32);
    if (original == NULL || compact_of == NULL) {
        Py_XDECREF(original);
        Py_XDECREF(compact_of);
        return NULL;
    }
    Py_BEGIN_ALLOW_THREADS
    compact_ids(alive.data, alive.size, PyArray_DATA(original), PyArray_DATA(compact_of));
    relabel_in_place(labels.data, labels.size, PyArray_DATA(compact_of));
    Py_END_ALLOW_THREADS
    return Py_BuildValue("(NNL)", original, compact_of, (long long)(live + 1));
}

KERNEL(count_contacts)
{
    Array labels;
    int64_t width, n, start, stop;
    if (check_nargs("count_contacts", nargs, 5) || array_arg(args[0], NPY_INT32, 1, 0, "labels", &labels)
        || int_arg(args[1], "width", &width) || int_arg(args[2], "n", &n) || int_arg(args[3], "start", &start)
        || int_arg(args[4], "stop", &stop)) {
        return NULL;
    }
    if (n < 1 || start < 0 || stop > labels.size || start > stop) {
        PyErr_Format(PyExc_ValueError, "count_contacts: need n >= 1 and 0 <= start <= stop <= labels.size");
        return NULL;
    }
    Counts counts;
    int status;
    Py_BEGIN_ALLOW_THREADS
    status = counted(labels.data, width, n, start, stop, &counts);
    Py_END_ALLOW_THREADS
    if (status < 0) {
        return PyErr_NoMemory();
    }
    return counts_tuple(&counts, n);
}

/* The arrays of a counts tuple (count_contacts's result) as arguments. */
typedef struct {
    Array pixels, keys, counts, meta, slots, total;
    int64_t used;
} CountsArg;

static int counts_arg(PyObject *obj, const char *what, CountsArg *out)
{
    PyObject *const *items = tuple_arg(obj, 7, what);
    if (items == NULL || array_arg(items[0], NPY_INT32, 1, 0, what, &out->pixels)
        || int_arg(items[1], what, &out->used) || array_arg(items[2], NPY_INT64, 1, 0, what, &out->keys)
        || array_arg(items[3], NPY_INT64, 1, 0, what, &out->counts)
        || array_arg(items[4], NPY_INT64, 1, 0, what, &out->meta)
        || array_arg(items[5], NPY_INT64, 1, 0, what, &out->slots)
        || array_arg(items[6], NPY_INT64, 1, 0, what, &out->total)) {
        return -1;
    }
    return 0;
}

/* Whether the arrays of a counts tuple fit together (after every argument's type was checked). */
static int counts_fit(const CountsArg *out, const char *what)
{
    if (out->meta.size != META_SIZE || out->keys.size != out->counts.size || out->used > out->pixels.size
        || out->slots.size != out->total.size * SLOTS) {
        PyErr_Format(PyExc_ValueError, "%s: not a tuple of contact counts", what);
        return -1;
    }
    return 0;
}

KERNEL(join_counts)
{
    CountsArg first, second;
    if (check_nargs("join_counts", nargs, 2) || counts_arg(args[0], "first", &first)
        || counts_arg(args[1], "second", &second) || counts_fit(&first, "first") || counts_fit(&second, "second")) {
        return NULL;
    }
    if (first.total.size != second.total.size) {
        PyErr_SetString(PyExc_ValueError, "join_counts: the two bands count different zones");
        return NULL;
    }
    int64_t n = first.total.size, used = first.used, used_b = second.used;
    /* The first band's arrays, extended (returned as they are where they did not grow). */
    int32_t *pixels = first.pixels.data, *grown_pixels = NULL;
    int64_t capacity = first.pixels.size;
    Table table = {first.keys.data, first.counts.data, first.meta.data, first.keys.size, 0};
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    if (used + used_b > capacity) {
        grown_pixels = calloc((size_t)(used + used_b), sizeof(int32_t));
        if (grown_pixels != NULL) {
            memcpy(grown_pixels, pixels, (size_t)capacity * sizeof(int32_t));
            pixels = grown_pixels;
            capacity = used + used_b;
        }
    }
    const int64_t *slots_b = second.slots.data, *keys_b = second.keys.data, *counts_b = second.counts.data;
    int64_t more = ((int64_t *)second.meta.data)[0];
    for (int64_t k = 0; k < second.slots.size; k++) {
        more += (k % SLOTS != 0 && slots_b[k] >= 0);
    }
    if ((used + used_b > first.pixels.size && grown_pixels == NULL) || table_reserve(&table, more) < 0) {
        failed = 1;
    } else {
        memcpy(pixels + used, second.pixels.data, (size_t)used_b * sizeof(int32_t));
        int64_t *total = first.total.data, *slots = first.slots.data;
        const int64_t *total_b = second.total.data;
        for (int64_t zone = 0; zone < n; zone++) {
            total[zone] += total_b[zone];
        }
        for (int64_t zone = 0; zone < n; zone++) {
            for (int64_t k = zone * SLOTS + 1; k < zone * SLOTS + SLOTS; k++) {
                if (slots_b[k] >= 0) {
                    contact_add(slots, &table, n, zone, slots_b[k] >> 32, slots_b[k] & COUNT_MASK, NULL);
                }
            }
        }
        for (int64_t slot = 0; slot < second.keys.size; slot++) {
            if (keys_b[slot] != EMPTY && counts_b[slot] != 0) {
                contact_add(slots, &table, n, keys_b[slot] / n, keys_b[slot] % n, counts_b[slot], NULL);
            }
        }
    }
    Py_END_ALLOW_THREADS
    if (failed) {
        free(grown_pixels);
        return PyErr_NoMemory();
    }
    PyObject *pixels_obj, *keys_obj, *counts_obj;
    npy_intp dims_pixels[1] = {capacity}, dims_table[1] = {table.size};
    if (grown_pixels != NULL) {
        pixels_obj = array_owning(grown_pixels, 1, dims_pixels, NPY_INT32);
    } else {
        pixels_obj = (PyObject *)first.pixels.array;
        Py_INCREF(pixels_obj);
    }
    if (table.owned) {
        int64_t *grown_counts = table.counts;
        keys_obj = array_owning(table.keys, 1, dims_table, NPY_INT64);
        counts_obj = array_owning(grown_counts, 1, dims_table, NPY_INT64);
    } else {
        keys_obj = (PyObject *)first.keys.array;
        counts_obj = (PyObject *)first.counts.array;
        Py_INCREF(keys_obj);
        Py_INCREF(counts_obj);
    }
    PyObject *result = NULL;
    if (pixels_obj != NULL && keys_obj != NULL && counts_obj != NULL) {
        result = Py_BuildValue("(OLOOOOO)", pixels_obj, (long long)(used + used_b), keys_obj, counts_obj,
                               first.meta.array, first.slots.array, first.total.array);
    }
    Py_XDECREF(pixels_obj);
    Py_XDECREF(keys_obj);
    Py_XDECREF(counts_obj);
    return result;
}

KERNEL(group_candidates)
{
    Array labels, pixels;
    int64_t used, n;
    if (check_nargs("group_candidates", nargs, 4) || array_arg(args[0], NPY_INT32, 1, 0, "labels", &labels)
        || array_arg(args[1], NPY_INT32, 1, 0, "pixels", &pixels) || int_arg(args[2], "used", &used)
        || int_arg(args[3], "n", &n)) {
        return NULL;
    }
    if (used < 0 || used > pixels.size || n < 0) {
        PyErr_SetString(PyExc_ValueError, "group_candidates: need 0 <= used <= len(pixels) and n >= 0");
        return NULL;
    }
    npy_intp room = used > 1 ? used : 1;
    PyArrayObject *grouped_arr = new_array_1d(room, NPY_INT32), *following_arr = new_array_1d(room, NPY_INT32);
    PyArrayObject *head_arr = new_array_1d(n, NPY_INT32), *tail_arr = new_array_1d(n, NPY_INT32);
    int64_t *start = calloc((size_t)(n + 1), sizeof(int64_t));
    if (grouped_arr == NULL || following_arr == NULL || head_arr == NULL || tail_arr == NULL || start == NULL) {
        Py_XDECREF(grouped_arr);
        Py_XDECREF(following_arr);
        Py_XDECREF(head_arr);
        Py_XDECREF(tail_arr);
        free(start);
        return start == NULL ? PyErr_NoMemory() : NULL;
    }
    const int32_t *label = labels.data, *candidates = pixels.data;
    int32_t *grouped = PyArray_DATA(grouped_arr), *following = PyArray_DATA(following_arr);
    int32_t *head = PyArray_DATA(head_arr), *tail = PyArray_DATA(tail_arr);
    Prefault prefault_grouped, prefault_following;
    Py_BEGIN_ALLOW_THREADS
    /* Both outputs are written whole: they fault in while the candidates are counted. */
    prefault_start(&prefault_grouped, grouped, (size_t)used * sizeof(int32_t));
    prefault_start(&prefault_following, following, (size_t)used * sizeof(int32_t));
    /* Each zone's candidates stored contiguously, in raster order: a fusion walks the list of
     * the zone it absorbs, and candidates in raster order of the whole image cost a cache
     * miss per row of a zone on large maps. */
    for (int64_t k = 0; k < used; k++) {
        start[label[candidates[k]] + 1] += 1;
    }
    prefault_join(&prefault_grouped);
    prefault_join(&prefault_following);
    for (int64_t zone = 0; zone < n; zone++) {
        start[zone + 1] += start[zone];
    }
    for (int64_t zone = 0; zone < n; zone++) {
        head[zone] = start[zone + 1] > start[zone] ? (int32_t)start[zone] : -1;
        tail[zone] = start[zone + 1] > start[zone] ? (int32_t)(start[zone + 1] - 1) : -1;
    }
    for (int64_t k = 0; k < used; k++) {
        int64_t zone = label[candidates[k]];
        grouped[start[zone]] = candidates[k];
        start[zone] += 1;
    }
    for (int64_t k = 0; k < used; k++) {
        following[k] = (int32_t)(k + 1);
    }
    for (int64_t zone = 0; zone < n; zone++) {
        if (tail[zone] != -1) {
            following[tail[zone]] = -1;
        }
    }
    Py_END_ALLOW_THREADS
    free(start);
    return Py_BuildValue("(NNNN)", grouped_arr, following_arr, head_arr, tail_arr);
}

/* contact_table's rows: every count of ``counts`` in original ids, into ``out`` (rows x 3) when
 * not NULL; returns the number of rows. */
static int64_t table_rows(const Counts *counts, int64_t n, const int32_t *original, int64_t *out)
{
    const int64_t *slots = counts->slots, *total = counts->total;
    const int64_t *keys = counts->table.keys, *values = counts->table.counts;
    int64_t row = 0;
    for (int64_t zone = 1; zone < n; zone++) {
        if (total[zone] > 0) {
            if (out != NULL) {
                out[3 * row] = original[zone - 1], out[3 * row + 1] = 0, out[3 * row + 2] = total[zone];
            }
            row += 1;
        }
        for (int64_t k = zone * SLOTS + 1; k < zone * SLOTS + SLOTS; k++) {
            if (slots[k] >= 0) {
                if (out != NULL) {
                    out[3 * row] = original[zone - 1];
                    out[3 * row + 1] = original[(slots[k] >> 32) - 1];
                    out[3 * row + 2] = slots[k] & COUNT_MASK;
                }
                row += 1;
            }
        }
    }
    for (int64_t slot = 0; slot < counts->table.size; slot++) {
        if (keys[slot] != EMPTY && values[slot] != 0) {
            if (out != NULL) {
                out[3 * row] = original[keys[slot] / n - 1];
                out[3 * row + 1] = original[keys[slot] % n - 1];
                out[3 * row + 2] = values[slot];
            }
            row += 1;
        }
    }
    return row;
}

KERNEL(contact_table)
{
    Array labels, alive;
    int64_t width;
    if (check_nargs("contact_table", nargs, 3) || array_arg(args[0], NPY_INT32, 1, 0, "labels", &labels)
        || int_arg(args[1], "width", &width) || array_arg(args[2], NPY_BOOL, 1, 0, "alive", &alive)) {
        return NULL;
    }
    int64_t *out = NULL, rows = 0;
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    int64_t live = count_alive(alive.data, alive.size), n = live + 1;
    int32_t *work = malloc((size_t)(labels.size > 0 ? labels.size : 1) * sizeof(int32_t));
    int32_t *original = malloc((size_t)(live > 0 ? live : 1) * sizeof(int32_t));
    int32_t *compact_of = malloc((size_t)(alive.size > 0 ? alive.size : 1) * sizeof(int32_t));
    Counts counts;
    if (work == NULL || original == NULL || compact_of == NULL) {
        failed = 1;
    } else {
        memcpy(work, labels.data, (size_t)labels.size * sizeof(int32_t));
        compact_ids(alive.data, alive.size, original, compact_of);
        relabel_in_place(work, labels.size, compact_of);
        if (counted(work, width, n, 0, labels.size, &counts) < 0) {
            failed = 1;
        } else {
            rows = table_rows(&counts, n, original, NULL);
            out = malloc((size_t)(rows > 0 ? 3 * rows : 1) * sizeof(int64_t));
            if (out == NULL) {
                failed = 1;
            } else {
                table_rows(&counts, n, original, out);
            }
            counts_release(&counts);
        }
    }
    free(work);
    free(original);
    free(compact_of);
    Py_END_ALLOW_THREADS
    if (failed) {
        return PyErr_NoMemory();
    }
    npy_intp dims[2] = {rows, 3};
    return array_owning(out, 2, dims, NPY_INT64);
}
