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

/* The node records of a graph being built: malloc'd, grown as edges are found. */
typedef struct {
    int32_t *data;
    int64_t capacity; /* in nodes */
    Prefault prefault;
} Nodes;

/* Room for two more nodes (0, or -1 out of memory, the nodes left as they were). realloc
 * moves a large block by remapping its pages, not by copying them. */
static int nodes_room(Nodes *nodes, int64_t used)
{
    if (used + 2 <= nodes->capacity) {
        return 0;
    }
    prefault_join(&nodes->prefault); /* it must not touch the block while it moves */
    int64_t capacity = nodes->capacity + nodes->capacity / 4 + 16;
    int32_t *grown = realloc(nodes->data, (size_t)capacity * 4 * sizeof(int32_t));
    if (grown == NULL) {
        return -1;
    }
    nodes->data = grown, nodes->capacity = capacity;
    return 0;
}

/* adjacency._contacts_in_order: scan the 4-contacts in raster order (each pixel against its
 * left, then its upper neighbour) and link the new edges. Returns the number of nodes used,
 * or -1 when out of memory.
 *
 * numba's kernel scans twice, first counting the pairs it would look up to size its node
 * array; here the array grows instead, which spares that scan (a tenth of a second at
 * 8000 x 8000 px). The edges and their order are the same. */
static int64_t contacts_in_order(const int32_t *restrict zones, int64_t rows, int64_t cols, int32_t *last_partner,
                                 int32_t *records, Nodes *nodes)
{
    int64_t n_nodes = 0;
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
                if (graph_find(records, nodes->data, a, b) != -1) {
                    continue;
                }
                if (nodes_room(nodes, n_nodes) < 0) {
                    return -1;
                }
                link_pair(records, nodes->data, n_nodes, a, b, NO_MINIMUM, 0);
                n_nodes += 2;
            }
        }
    }
    return n_nodes;
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
    /* Room for 4.5 nodes per zone to start with: a planar graph has fewer than 6 (three edges
     * per zone), and the flat zones of maps have 4.1-4.4; more room is made as they come. */
    Nodes nodes = {NULL, count * 9 / 2 + 16, {0}};
    nodes.data = malloc((size_t)nodes.capacity * 4 * sizeof(int32_t));
    if (records == NULL || last_partner == NULL || nodes.data == NULL) {
        Py_XDECREF(records);
        free(last_partner);
        free(nodes.data);
        return records == NULL ? NULL : PyErr_NoMemory();
    }
    int32_t *rec = PyArray_DATA(records);
    int64_t n_nodes;
    Py_BEGIN_ALLOW_THREADS
    /* The nodes are written nearly whole, in order: they fault in on another thread while the
     * records are set and the first edges linked. */
    advise_huge_pages(nodes.data, (size_t)nodes.capacity * 4 * sizeof(int32_t));
    prefault_start(&nodes.prefault, nodes.data, (size_t)(count * 4) * 4 * sizeof(int32_t));
    isolated_zones(rec, value.data, count);
    n_nodes = contacts_in_order(zones.data, zones.rows, zones.cols, last_partner, rec, &nodes);
    prefault_join(&nodes.prefault);
    Py_END_ALLOW_THREADS
    free(last_partner);
    if (n_nodes < 0) {
        Py_DECREF(records);
        free(nodes.data);
        return PyErr_NoMemory();
    }
    /* The node records are the used ones (at least a pair, as numba's): the rest goes back. */
    int64_t kept = n_nodes > 2 ? n_nodes : 2;
    int32_t *shrunk = realloc(nodes.data, (size_t)kept * 4 * sizeof(int32_t));
    nodes.data = shrunk != NULL ? shrunk : nodes.data;
    if (n_nodes < kept) {
        memset(nodes.data + 4 * n_nodes, 0, (size_t)(kept - n_nodes) * 4 * sizeof(int32_t));
    }
    npy_intp dims[2] = {kept, 4};
    PyObject *node_array = array_owning(nodes.data, 2, dims, NPY_INT32);
    if (node_array == NULL) {
        Py_DECREF(records);
        return NULL;
    }
    return Py_BuildValue("(NN)", records, node_array);
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
