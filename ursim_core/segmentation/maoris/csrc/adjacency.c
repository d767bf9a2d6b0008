/* The compact MAORIS zone graph in C: building it, small-zone removal, compacting and expanding
 * (port of ../kernels/adjacency.py; the layout and the edge operations are in graph.h).
 *
 * Node arrays are allocated zeroed where numba's were np.empty: rows a kernel never writes are
 * never read, so only their (meaningless) content differs. */
#include "graph.h"
#include "kernels.h"

/* Records of isolated zones, zone z of value value[z]. */
static void isolated_zones(int32_t *records, const int32_t *value, int64_t count)
{
    for (int64_t zone = 0; zone < count; zone++) {
        REC(records, zone, HEAD) = -1;
        REC(records, zone, TAIL) = -1;
        REC(records, zone, DEGREE) = 0;
        REC(records, zone, VALUE) = value[zone];
    }
}

static inline void link_pair(int32_t *records, int32_t *nodes, int64_t node, int64_t a, int64_t b, int32_t minimum,
                             int32_t unbreakable)
{
    graph_append(records, nodes, a, node, b);
    graph_append(records, nodes, b, node + 1, a);
    NODE(nodes, node, ATTRIBUTE) = minimum;
    NODE(nodes, node + 1, ATTRIBUTE) = unbreakable;
}

/* adjacency._contacts_in_order: scan the 4-contacts in raster order (each pixel against its
 * left, then its upper neighbour) and link the new edges; with count_only, how many pairs would
 * be looked up (a bound on the number of edges); else the number of nodes used. */
static int64_t contacts_in_order(const int32_t *restrict zones, int64_t rows, int64_t cols, int32_t *last_partner,
                                 int32_t *records, int32_t *nodes, int count_only)
{
    int64_t n_candidates = 0, n_nodes = 0;
    for (int64_t row = 0; row < rows; row++) {
        const int32_t *line = zones + row * cols;
        int64_t last_left_a = -1, last_left_b = -1;
        for (int64_t col = 0; col < cols; col++) {
            int64_t here = line[col];
            if (here == 0) {
                continue;
            }
            for (int kind = 0; kind < 2; kind++) {
                int64_t other;
                if (kind == 0) {
                    if (col == 0) {
                        continue;
                    }
                    other = line[col - 1];
                } else {
                    if (row == 0) {
                        continue;
                    }
                    other = line[col - cols];
                }
                if (other == 0 || other == here) {
                    continue;
                }
                int64_t a = here < other ? here : other, b = here < other ? other : here;
                if (kind == 0) {
                    if (a == last_left_a && b == last_left_b) {
                        continue;
                    }
                    last_left_a = a;
                    last_left_b = b;
                } else if (col > 0 && line[col - 1] == here && line[col - 1 - cols] == other) {
                    continue; /* same pair as the pixel to the left */
                }
                if (last_partner[a] == b || last_partner[b] == a) {
                    continue;
                }
                last_partner[a] = (int32_t)b;
                last_partner[b] = (int32_t)a;
                n_candidates += 1;
                if (count_only || graph_find(records, nodes, a, b) != -1) {
                    continue;
                }
                link_pair(records, nodes, n_nodes, a, b, NO_MINIMUM, 0);
                n_nodes += 2;
            }
        }
    }
    return count_only ? n_candidates : n_nodes;
}

KERNEL(build_adjacency)
{
    Array zones, value;
    if (check_nargs("build_adjacency", nargs, 2) || array_arg(args[0], NPY_INT32, 2, 0, "zones", &zones)
        || array_arg(args[1], NPY_INT32, 1, 0, "value", &value)) {
        return NULL;
    }
    int64_t count = value.size;
    PyArrayObject *records = new_array_2d(count, 4, NPY_INT32);
    int32_t *last_partner = calloc((size_t)(count > 0 ? count : 1), sizeof(int32_t));
    if (records == NULL || last_partner == NULL) {
        Py_XDECREF(records);
        free(last_partner);
        return records == NULL ? NULL : PyErr_NoMemory();
    }
    int32_t *rec = PyArray_DATA(records);
    int64_t bound;
    Prefault prefault;
    Py_BEGIN_ALLOW_THREADS
    /* The records fault in while the contacts are counted (which does not read them). */
    prefault_start(&prefault, rec, (size_t)count * 4 * sizeof(int32_t));
    bound = contacts_in_order(zones.data, zones.rows, zones.cols, last_partner, rec, NULL, 1);
    prefault_join(&prefault);
    isolated_zones(rec, value.data, count);
    memset(last_partner, 0, (size_t)count * sizeof(int32_t));
    Py_END_ALLOW_THREADS
    int64_t n_nodes = 2 * bound > 2 ? 2 * bound : 2;
    PyArrayObject *nodes = (PyArrayObject *)PyArray_ZEROS(2, ((npy_intp[]){n_nodes, 4}), NPY_INT32, 0);
    if (nodes == NULL) {
        Py_DECREF(records);
        free(last_partner);
        return NULL;
    }
    int32_t *nod = PyArray_DATA(nodes);
    Py_BEGIN_ALLOW_THREADS
    /* Nearly every node is written (the bound is within a few % of the edges): they fault in
     * ahead of the scan that links them. */
    prefault_start(&prefault, nod, (size_t)n_nodes * 4 * sizeof(int32_t));
    contacts_in_order(zones.data, zones.rows, zones.cols, last_partner, rec, nod, 0);
    prefault_join(&prefault);
    Py_END_ALLOW_THREADS
    free(last_partner);
    return Py_BuildValue("(NN)", records, nodes);
}

KERNEL(_link_entries)
{
    Array zone, other, owner, minimum, unbreakable, value;
    if (check_nargs("_link_entries", nargs, 6) || array_arg(args[0], NPY_INT32, 1, 0, "zone", &zone)
        || array_arg(args[1], NPY_INT32, 1, 0, "other", &other) || array_arg(args[2], NPY_INT64, 1, 0, "owner", &owner)
        || array_arg(args[3], NPY_INT32, 1, 0, "minimum", &minimum)
        || array_arg(args[4], NPY_BOOL, 1, 0, "unbreakable", &unbreakable)
        || array_arg(args[5], NPY_INT32, 1, 0, "value", &value)) {
        return NULL;
    }
    int64_t n = zone.size;
    PyArrayObject *records = new_array_2d(value.size, 4, NPY_INT32);
    PyArrayObject *nodes = (PyArrayObject *)PyArray_ZEROS(2, ((npy_intp[]){2 * n > 2 ? 2 * n : 2, 4}), NPY_INT32, 0);
    if (records == NULL || nodes == NULL) {
        Py_XDECREF(records);
        Py_XDECREF(nodes);
        return NULL;
    }
    int32_t *rec = PyArray_DATA(records), *nod = PyArray_DATA(nodes);
    const int32_t *zones = zone.data, *others = other.data, *minimums = minimum.data;
    const int64_t *owners = owner.data;
    const npy_bool *unbreakables = unbreakable.data;
    Py_BEGIN_ALLOW_THREADS
    isolated_zones(rec, value.data, value.size);
    for (int64_t i = 0; i < n; i++) {
        int64_t node = zones[i] < others[i] ? 2 * owners[i] : 2 * owners[i] + 1;
        graph_append(rec, nod, zones[i], node, others[i]);
        if (zones[i] < others[i]) {
            NODE(nod, node, ATTRIBUTE) = minimums[i];
            NODE(nod, node + 1, ATTRIBUTE) = unbreakables[i];
        }
    }
    Py_END_ALLOW_THREADS
    return Py_BuildValue("(NN)", records, nodes);
}

KERNEL(adjacency_entries)
{
    Array alive_arg;
    Graph graph;
    if (check_nargs("adjacency_entries", nargs, 2) || array_arg(args[0], NPY_BOOL, 1, 0, "alive", &alive_arg)
        || graph_arg(args[1], "graph", &graph)) {
        return NULL;
    }
    const npy_bool *alive = alive_arg.data;
    int32_t *records = graph.records, *nodes = graph.nodes;
    int64_t total = 0;
    for (int64_t zone = 0; zone < alive_arg.size; zone++) {
        if (alive[zone]) {
            total += REC(records, zone, DEGREE);
        }
    }
    PyArrayObject *out = new_array_2d(total, 6, NPY_INT64);
    if (out == NULL) {
        return NULL;
    }
    int64_t *o = PyArray_DATA(out);
    Py_BEGIN_ALLOW_THREADS
    int64_t k = 0;
    for (int64_t zone = 0; zone < alive_arg.size; zone++) {
        if (!alive[zone]) {
            continue;
        }
        for (int64_t node = REC(records, zone, HEAD); node != -1; node = NODE(nodes, node, NEXT)) {
            int64_t *row = o + 6 * k++;
            row[0] = zone;
            row[1] = NODE(nodes, node, NEIGHBOUR);
            row[2] = node;
            row[3] = node ^ 1;
            row[4] = NODE(nodes, node & ~(int64_t)1, ATTRIBUTE);
            row[5] = NODE(nodes, node | 1, ATTRIBUTE);
        }
    }
    Py_END_ALLOW_THREADS
    return (PyObject *)out;
}

KERNEL(remove_small_zones)
{
    int64_t min_size;
    Array size_arg, alive_arg, parent_arg;
    Graph graph;
    if (check_nargs("remove_small_zones", nargs, 5) || int_arg(args[0], "min_size", &min_size)
        || array_arg(args[1], NPY_INT64, 1, 0, "size", &size_arg)
        || array_arg(args[2], NPY_BOOL, 1, 0, "alive", &alive_arg)
        || array_arg(args[3], NPY_INT32, 1, 0, "parent", &parent_arg) || graph_arg(args[4], "graph", &graph)) {
        return NULL;
    }
    int64_t *size = size_arg.data;
    npy_bool *alive = alive_arg.data;
    int32_t *parent = parent_arg.data, *records = graph.records, *nodes = graph.nodes;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t zone = 1; zone < graph.n_records; zone++) {
        if (!alive[zone] || size[zone] >= min_size) {
            continue;
        }
        alive[zone] = 0;
        if (REC(records, zone, DEGREE) == 0) {
            parent[zone] = 0;
            continue;
        }
        int64_t zone_value = REC(records, zone, VALUE);
        int64_t closest = -1, closest_gap = (int64_t)1 << 30;
        for (int64_t node = REC(records, zone, HEAD); node != -1; node = NODE(nodes, node, NEXT)) {
            int64_t other = NODE(nodes, node, NEIGHBOUR);
            int64_t gap = REC(records, other, VALUE) - zone_value;
            gap = gap < 0 ? -gap : gap;
            if (gap < closest_gap) {
                closest = other;
                closest_gap = gap;
            }
        }
        parent[zone] = (int32_t)closest;
        size[closest] += size[zone];
        graph_fuse_edges(zone, closest, records, nodes);
    }
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

KERNEL(compact_graph)
{
    Array original_arg, compact_of_arg;
    Graph graph;
    if (check_nargs("compact_graph", nargs, 3) || array_arg(args[0], NPY_INT32, 1, 0, "original", &original_arg)
        || array_arg(args[1], NPY_INT32, 1, 0, "compact_of", &compact_of_arg) || graph_arg(args[2], "graph", &graph)) {
        return NULL;
    }
    const int32_t *original = original_arg.data, *compact_of = compact_of_arg.data;
    int32_t *records = graph.records, *nodes = graph.nodes;
    int64_t n = original_arg.size + 1, total = 0;
    for (int64_t k = 0; k < original_arg.size; k++) {
        total += REC(records, original[k], DEGREE);
    }
    PyArrayObject *compact_records = new_array_2d(n, 4, NPY_INT32);
    PyArrayObject *compact_nodes =
        (PyArrayObject *)PyArray_ZEROS(2, ((npy_intp[]){total > 2 ? total : 2, 4}), NPY_INT32, 0);
    if (compact_records == NULL || compact_nodes == NULL) {
        Py_XDECREF(compact_records);
        Py_XDECREF(compact_nodes);
        return NULL;
    }
    int32_t *crec = PyArray_DATA(compact_records), *cnod = PyArray_DATA(compact_nodes);
    Py_BEGIN_ALLOW_THREADS
    for (int64_t zone = 0; zone < n; zone++) {
        REC(crec, zone, HEAD) = -1;
        REC(crec, zone, TAIL) = -1;
        REC(crec, zone, DEGREE) = 0;
        REC(crec, zone, VALUE) = zone > 0 ? REC(records, original[zone - 1], VALUE) : 0;
    }
    int64_t pairs = 0;
    for (int64_t k = 0; k < original_arg.size; k++) {
        int64_t a = k + 1;
        for (int64_t node = REC(records, original[k], HEAD); node != -1; node = NODE(nodes, node, NEXT)) {
            int64_t b = compact_of[NODE(nodes, node, NEIGHBOUR)], new_node;
            if (b > a) {
                /* The first end met of an edge takes the next pair, with the same parity. */
                new_node = 2 * pairs + (node & 1);
                pairs += 1;
                NODE(nodes, node ^ 1, PREVIOUS) = (int32_t)(new_node ^ 1);
                NODE(cnod, new_node & ~(int64_t)1, ATTRIBUTE) = NODE(nodes, node & ~(int64_t)1, ATTRIBUTE);
                NODE(cnod, new_node | 1, ATTRIBUTE) = NODE(nodes, node | 1, ATTRIBUTE);
            } else {
                new_node = NODE(nodes, node, PREVIOUS);
            }
            graph_append(crec, cnod, a, new_node, b);
        }
    }
    Py_END_ALLOW_THREADS
    return Py_BuildValue("(NN)", compact_records, compact_nodes);
}

KERNEL(expand_graph)
{
    Array original_arg, records_arg;
    Graph compact;
    if (check_nargs("expand_graph", nargs, 3) || array_arg(args[0], NPY_INT32, 1, 0, "original", &original_arg)
        || graph_arg(args[1], "compact", &compact) || array_arg(args[2], NPY_INT32, 2, 0, "records", &records_arg)) {
        return NULL;
    }
    const int32_t *original = original_arg.data;
    int32_t *records = records_arg.data, *crec = compact.records, *cnod = compact.nodes;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t k = 0; k < original_arg.size; k++) {
        int64_t zone = original[k];
        REC(records, zone, HEAD) = REC(crec, k + 1, HEAD);
        REC(records, zone, TAIL) = REC(crec, k + 1, TAIL);
        REC(records, zone, DEGREE) = REC(crec, k + 1, DEGREE);
        for (int64_t node = REC(crec, k + 1, HEAD); node != -1; node = NODE(cnod, node, NEXT)) {
            NODE(cnod, node, NEIGHBOUR) = original[NODE(cnod, node, NEIGHBOUR) - 1];
        }
    }
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}
