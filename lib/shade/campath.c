/* SPDX-License-Identifier: Apache-2.0 */
/* Camera paths: keyframes read from YAML (libyaml's document API, which
 * keeps line and column marks for every node), interpolated linearly or
 * with a uniform Catmull-Rom spline. */
#include "shade/shade.h"

#include "core/yaml_doc.h"

#include <stdlib.h>
#include <string.h>

#define MAX_FRAMES 1000000

static int scalar_is(const yaml_node_t *n, const char *s)
{
    return n->type == YAML_SCALAR_NODE && strcmp((const char *)n->data.scalar.value, s) == 0;
}

static lie_status get_vec3(lie_yaml *p, const yaml_node_t *n, const char *key, lie_vec3 *out)
{
    double v[3];
    lie_status st = lie_yaml_numbers(p, n, key, v, 3);
    if (st != LIE_OK)
        return st;
    *out = lie_v3((float)v[0], (float)v[1], (float)v[2]);
    return LIE_OK;
}

static lie_status parse_key(lie_yaml *p, const yaml_node_t *n, int index, float prev_fov, lie_camera_key *k)
{
    char key[64];
    snprintf(key, sizeof key, "keys[%d]", index);
    if (n->type != YAML_MAPPING_NODE)
        return lie_yaml_error(p, n, key, "expected a mapping with eye, target, up, fov, frames");
    int have_eye = 0, have_target = 0;
    k->up = lie_v3(0.0f, 1.0f, 0.0f);
    k->fov_deg = prev_fov;
    k->frames = 1;
    for (yaml_node_pair_t *pr = n->data.mapping.pairs.start; pr < n->data.mapping.pairs.top; pr++) {
        yaml_node_t *kn = yaml_document_get_node(&p->doc, pr->key);
        yaml_node_t *vn = yaml_document_get_node(&p->doc, pr->value);
        if (!kn || !vn || kn->type != YAML_SCALAR_NODE)
            return lie_yaml_error(p, n, key, "keys must be plain names");
        char sub[128];
        snprintf(sub, sizeof sub, "%s.%s", key, (const char *)kn->data.scalar.value);
        lie_status st = LIE_OK;
        if (scalar_is(kn, "eye")) {
            st = get_vec3(p, vn, sub, &k->eye);
            have_eye = 1;
        } else if (scalar_is(kn, "target")) {
            st = get_vec3(p, vn, sub, &k->target);
            have_target = 1;
        } else if (scalar_is(kn, "up")) {
            st = get_vec3(p, vn, sub, &k->up);
        } else if (scalar_is(kn, "fov")) {
            double f = 0.0;
            st = lie_yaml_number(p, vn, sub, &f);
            if (st == LIE_OK && !(f > 0.0 && f < 180.0))
                return lie_yaml_error(p, vn, sub, "expected a number in (0, 180)");
            if (st == LIE_OK)
                k->fov_deg = (float)f;
        } else if (scalar_is(kn, "frames")) {
            double f = 0.0;
            st = lie_yaml_number(p, vn, sub, &f);
            if (st == LIE_OK && !(f >= 1.0 && f <= MAX_FRAMES && f == floor(f)))
                return lie_yaml_error(p, vn, sub, "expected an integer in 1..1000000");
            if (st == LIE_OK) /* converted only once in range: a cast out of range is undefined */
                k->frames = (int)f;
        } else {
            return lie_yaml_error(p, kn, sub, "unknown key (expected eye, target, up, fov or frames)");
        }
        if (st != LIE_OK)
            return st;
    }
    if (!have_eye)
        return lie_yaml_error(p, n, key, "missing eye");
    if (!have_target)
        return lie_yaml_error(p, n, key, "missing target");
    if (!lie_v3_within(k->eye, LIE_CAMERA_COORD_MAX) || !lie_v3_within(k->target, LIE_CAMERA_COORD_MAX))
        return lie_yaml_error(p, n, key, "eye and target must lie within +-1e14 (the coordinate range)");
    lie_vec3 f = lie_v3_sub(k->target, k->eye);
    if (!(lie_v3_len(f) > 0.0f))
        return lie_yaml_error(p, n, key, "eye and target coincide");
    if (!(lie_v3_len(lie_v3_cross(lie_v3_norm(f), k->up)) > 1e-6f))
        return lie_yaml_error(p, n, key, "up is parallel to the view direction");
    return LIE_OK;
}

static lie_status check_frames(const lie_camera_path *p, const char *name, lie_error *err);

lie_status lie_camera_path_parse(const unsigned char *text, size_t size, const char *name,
                                 lie_camera_path **out, lie_error *err)
{
    *out = NULL;
    lie_yaml p;
    lie_status lst = lie_yaml_load(&p, text, size, name, err);
    if (lst != LIE_OK)
        return lst;
    lie_status st = LIE_OK;
    lie_camera_path *cp = calloc(1, sizeof *cp);
    yaml_node_t *root = yaml_document_get_root_node(&p.doc);
    if (!cp) {
        st = lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    } else if (!root) {
        st = lie_error_set(err, LIE_ERR_FORMAT, name, "empty document: expected a mapping with keys");
    } else if (root->type != YAML_MAPPING_NODE) {
        st = lie_yaml_error(&p, root, "document", "expected a mapping with keys and interpolation");
    }
    if (cp)
        cp->smooth = 1;
    const yaml_node_t *keys = NULL;
    for (yaml_node_pair_t *pr = st == LIE_OK ? root->data.mapping.pairs.start : NULL;
         st == LIE_OK && pr < root->data.mapping.pairs.top; pr++) {
        yaml_node_t *kn = yaml_document_get_node(&p.doc, pr->key);
        yaml_node_t *vn = yaml_document_get_node(&p.doc, pr->value);
        if (!kn || !vn || kn->type != YAML_SCALAR_NODE)
            st = lie_yaml_error(&p, root, "document", "keys must be plain names");
        else if (scalar_is(kn, "keys"))
            keys = vn;
        else if (scalar_is(kn, "interpolation")) {
            if (scalar_is(vn, "linear"))
                cp->smooth = 0;
            else if (scalar_is(vn, "smooth"))
                cp->smooth = 1;
            else
                st = lie_yaml_error(&p, vn, "interpolation", "expected linear or smooth");
        } else if (scalar_is(kn, "first-frame")) {
            double x = 0.0;
            st = lie_yaml_number(&p, vn, "first-frame", &x);
            if (st == LIE_OK && !(x >= 0.0 && x <= MAX_FRAMES && x == floor(x)))
                st = lie_yaml_error(&p, vn, "first-frame", "expected an integer in [0, 1000000]");
            if (st == LIE_OK) /* converted only once in range: a cast out of range is undefined */
                cp->first = (int)x;
        } else {
            char k[128];
            snprintf(k, sizeof k, "%s", (const char *)kn->data.scalar.value);
            st = lie_yaml_error(&p, kn, k, "unknown key (expected keys, interpolation or first-frame)");
        }
    }
    if (st == LIE_OK && !keys)
        st = lie_yaml_error(&p, root, "keys", "missing");
    if (st == LIE_OK && (keys->type != YAML_SEQUENCE_NODE || keys->data.sequence.items.top == keys->data.sequence.items.start))
        st = lie_yaml_error(&p, keys, "keys", "expected a sequence of at least one key");
    if (st == LIE_OK) {
        int n = (int)(keys->data.sequence.items.top - keys->data.sequence.items.start);
        cp->keys = calloc((size_t)n, sizeof *cp->keys);
        if (!cp->keys)
            st = lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
        float fov = 45.0f;
        long frames = 0;
        for (int i = 0; st == LIE_OK && i < n; i++) {
            yaml_node_t *kn = yaml_document_get_node(&p.doc, keys->data.sequence.items.start[i]);
            if (!kn) {
                st = lie_yaml_error(&p, keys, "keys", "malformed sequence");
                break;
            }
            st = parse_key(&p, kn, i, fov, &cp->keys[i]);
            if (st != LIE_OK)
                break;
            cp->n_keys = i + 1;
            fov = cp->keys[i].fov_deg;
            frames += i + 1 < n ? cp->keys[i].frames : 1;
            if (frames > MAX_FRAMES)
                st = lie_yaml_error(&p, kn, "keys", "more than 1000000 frames");
        }
        cp->n_frames = (int)frames;
    }
    lie_yaml_free(&p);
    if (st == LIE_OK)
        st = check_frames(cp, name, err);
    if (st != LIE_OK) {
        lie_camera_path_destroy(cp);
        return st;
    }
    *out = cp;
    return LIE_OK;
}

lie_status lie_camera_path_read(const char *path, lie_camera_path **out, lie_error *err)
{
    unsigned char *data;
    size_t size;
    lie_status st = lie_read_file_max(path, LIE_READ_MAX_TEXT, &data, &size, err);
    if (st != LIE_OK)
        return st;
    st = lie_camera_path_parse(data, size, path, out, err);
    free(data);
    return st;
}

void lie_camera_path_destroy(lie_camera_path *p)
{
    if (!p)
        return;
    free(p->keys);
    free(p);
}

/* Uniform Catmull-Rom through p1..p2 with neighbours p0, p3. */
static float catmull_rom(float p0, float p1, float p2, float p3, float t)
{
    float t2 = t * t, t3 = t2 * t;
    return 0.5f * (2.0f * p1 + (p2 - p0) * t + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * t2 +
                   (3.0f * p1 - p0 - 3.0f * p2 + p3) * t3);
}

static lie_vec3 interp3(const lie_camera_path *p, int i, float t, size_t offset)
{
    int n = p->n_keys;
    int i0 = i > 0 ? i - 1 : 0, i2 = i + 1 < n ? i + 1 : n - 1, i3 = i + 2 < n ? i + 2 : n - 1;
    const lie_vec3 *a = (const lie_vec3 *)((const char *)&p->keys[i0] + offset);
    const lie_vec3 *b = (const lie_vec3 *)((const char *)&p->keys[i] + offset);
    const lie_vec3 *c = (const lie_vec3 *)((const char *)&p->keys[i2] + offset);
    const lie_vec3 *d = (const lie_vec3 *)((const char *)&p->keys[i3] + offset);
    if (!p->smooth)
        return lie_v3_add(lie_v3_scale(*b, 1.0f - t), lie_v3_scale(*c, t));
    return lie_v3(catmull_rom(a->x, b->x, c->x, d->x, t), catmull_rom(a->y, b->y, c->y, d->y, t),
                  catmull_rom(a->z, b->z, c->z, d->z, t));
}

/* The camera at parameter t in [0, 1) of the span from key i. */
static lie_camera frame_at(const lie_camera_path *p, int i, float t)
{
    lie_vec3 eye = interp3(p, i, t, offsetof(lie_camera_key, eye));
    lie_vec3 target = interp3(p, i, t, offsetof(lie_camera_key, target));
    lie_vec3 up = interp3(p, i, t, offsetof(lie_camera_key, up));
    int i2 = i + 1 < p->n_keys ? i + 1 : i;
    float fov = p->keys[i].fov_deg * (1.0f - t) + p->keys[i2].fov_deg * t;
    lie_camera c;
    memset(&c, 0, sizeof c);
    c.eye = eye;
    c.forward = lie_v3_norm(lie_v3_sub(target, eye));
    lie_vec3 u = lie_v3_sub(up, lie_v3_scale(c.forward, lie_v3_dot(up, c.forward)));
    if (!(lie_v3_len(u) > 1e-6f))
        u = fabsf(c.forward.y) < 0.9f ? lie_v3(0, 1, 0) : lie_v3(1, 0, 0);
    c.up = lie_v3_norm(lie_v3_sub(u, lie_v3_scale(c.forward, lie_v3_dot(u, c.forward))));
    c.yfov = fov * (float)M_PI / 180.0f;
    return c;
}

static float span_t(const lie_camera_path *p, int i, int f)
{
    return i + 1 < p->n_keys ? (float)f / (float)p->keys[i].frames : 0.0f;
}

lie_camera lie_camera_path_frame(const lie_camera_path *p, int frame)
{
    int i = 0;
    int f = frame;
    while (i + 1 < p->n_keys && f >= p->keys[i].frames) {
        f -= p->keys[i].frames;
        i++;
    }
    return frame_at(p, i, span_t(p, i, f));
}

/* Every frame a renderer will be given, as lie_camera_parse checks one
 * --camera: valid keys can still interpolate to a frame whose eye meets its
 * target (keys that swap them), or a spline overshoot past the range. */
static lie_status check_frames(const lie_camera_path *p, const char *name, lie_error *err)
{
    long frame = 0;
    for (int i = 0; i < p->n_keys; i++) {
        int n = i + 1 < p->n_keys ? p->keys[i].frames : 1;
        for (int f = 0; f < n; f++, frame++) {
            lie_camera c = frame_at(p, i, span_t(p, i, f));
            const char *bad = lie_camera_invalid(&c);
            if (bad)
                return lie_error_set(err, LIE_ERR_FORMAT, name, "frame %ld (between keys[%d] and keys[%d]): %s",
                                     p->first + frame, i, i + 1 < p->n_keys ? i + 1 : i, bad);
        }
    }
    return LIE_OK;
}

lie_status lie_camera_path_write(const lie_camera_path *p, const char *path, lie_error *err)
{
    lie_atomic_file af;
    lie_status st = lie_atomic_open(&af, path, err);
    if (st != LIE_OK)
        return st;
    FILE *fp = af.fp;
    fprintf(fp, "interpolation: %s\n", p->smooth ? "smooth" : "linear");
    if (p->first)
        fprintf(fp, "first-frame: %d\n", p->first);
    fprintf(fp, "keys:\n");
    for (int i = 0; i < p->n_keys; i++) {
        const lie_camera_key *k = &p->keys[i];
        fprintf(fp, "  - eye: [%.9g, %.9g, %.9g]\n", (double)k->eye.x, (double)k->eye.y, (double)k->eye.z);
        fprintf(fp, "    target: [%.9g, %.9g, %.9g]\n", (double)k->target.x, (double)k->target.y,
                (double)k->target.z);
        fprintf(fp, "    up: [%.9g, %.9g, %.9g]\n", (double)k->up.x, (double)k->up.y, (double)k->up.z);
        fprintf(fp, "    fov: %.9g\n", (double)k->fov_deg);
        if (i + 1 < p->n_keys)
            fprintf(fp, "    frames: %d\n", k->frames);
    }
    if (ferror(fp)) {
        lie_atomic_abort(&af);
        return lie_error_set(err, LIE_ERR_IO, path, "write failed");
    }
    return lie_atomic_commit(&af, err);
}
