/* The per-tick kernels of the cell and the controller, in C: the same operations, in the same
 * order, as the Python floats they replace, so that a tick gives the same bits as before and on
 * every x86-64 CPU.
 *
 * Bit-identity rests on three rules, kept by the build (setup.py) and by this file:
 *   - every double operation is rounded once, in the order written: no fused multiply-add
 *     (-ffp-contract=off), no reassociation (no -ffast-math), SSE2 doubles (x86-64);
 *   - libm is called for sin, cos, acos and pow as CPython's math module and float ** do
 *     (-fno-builtin: gcc neither folds pow(x, 2.0) into x * x nor fuses sin and cos);
 *   - the small matrix products and the Cholesky solve are MuJoCo's own routines.
 * Each function names the Python it mirrors (src/vgs/vecmath.py, control/arm.py, ...); the
 * golden records (tests/test_golden_records.py, tests/test_kernels.py) hold the two equal.
 *
 * MuJoCo's symbols resolve against the libmujoco that the mujoco package has loaded
 * (src/vgs/native.py makes it global before importing this module).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mujoco/mujoco.h>

/* ------------------------------------------------------------------------------------------
 * vecmath: flat row-major 3x3 matrices, 3-vectors (src/vgs/vecmath.py)
 * ---------------------------------------------------------------------------------------- */

static void mv(const double* R, const double* v, double* out) {
    double x = v[0], y = v[1], z = v[2];
    out[0] = R[0] * x + R[1] * y + R[2] * z;
    out[1] = R[3] * x + R[4] * y + R[5] * z;
    out[2] = R[6] * x + R[7] * y + R[8] * z;
}

static void mtv(const double* R, const double* v, double* out) {
    double x = v[0], y = v[1], z = v[2];
    out[0] = R[0] * x + R[3] * y + R[6] * z;
    out[1] = R[1] * x + R[4] * y + R[7] * z;
    out[2] = R[2] * x + R[5] * y + R[8] * z;
}

static void mm(const double* a, const double* b, double* out) {
    double r[9];
    r[0] = a[0] * b[0] + a[1] * b[3] + a[2] * b[6];
    r[1] = a[0] * b[1] + a[1] * b[4] + a[2] * b[7];
    r[2] = a[0] * b[2] + a[1] * b[5] + a[2] * b[8];
    r[3] = a[3] * b[0] + a[4] * b[3] + a[5] * b[6];
    r[4] = a[3] * b[1] + a[4] * b[4] + a[5] * b[7];
    r[5] = a[3] * b[2] + a[4] * b[5] + a[5] * b[8];
    r[6] = a[6] * b[0] + a[7] * b[3] + a[8] * b[6];
    r[7] = a[6] * b[1] + a[7] * b[4] + a[8] * b[7];
    r[8] = a[6] * b[2] + a[7] * b[5] + a[8] * b[8];
    memcpy(out, r, sizeof r);
}

static void transpose(const double* R, double* out) {
    double r[9] = {R[0], R[3], R[6], R[1], R[4], R[7], R[2], R[5], R[8]};
    memcpy(out, r, sizeof r);
}

/* A B^T: mm(A, transpose(B)) */
static void mmt(const double* a, const double* b, double* out) {
    double bt[9];
    transpose(b, bt);
    mm(a, bt, out);
}

/* A^T B: mm(transpose(A), B) */
static void mtm(const double* a, const double* b, double* out) {
    double at[9];
    transpose(a, at);
    mm(at, b, out);
}

static double norm3(const double* v) {
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* vecmath.exp_so3 (Rodrigues) */
static void exp_so3(double w0, double w1, double w2, double* out) {
    double theta = sqrt(w0 * w0 + w1 * w1 + w2 * w2);
    if (theta < 1e-12) {
        double r[9] = {1.0, -w2, w1, w2, 1.0, -w0, -w1, w0, 1.0};
        memcpy(out, r, sizeof r);
        return;
    }
    double x = w0 / theta, y = w1 / theta, z = w2 / theta;
    double s = sin(theta), c = 1.0 - cos(theta);
    double xy = c * x * y, xz = c * x * z, yz = c * y * z;
    out[0] = 1.0 - c * (y * y + z * z);
    out[1] = xy - s * z;
    out[2] = xz + s * y;
    out[3] = xy + s * z;
    out[4] = 1.0 - c * (x * x + z * z);
    out[5] = yz - s * x;
    out[6] = xz - s * y;
    out[7] = yz + s * x;
    out[8] = 1.0 - c * (x * x + y * y);
}

/* Python's min(a, b) and max(a, b) on floats: the first argument unless the second is
 * strictly smaller (larger). */
static double py_min(double a, double b) { return b < a ? b : a; }
static double py_max(double a, double b) { return b > a ? b : a; }

/* vecmath.log_so3 */
static void log_so3(const double* R, double* out) {
    double cos_t = py_max(-1.0, py_min(1.0, 0.5 * (R[0] + R[4] + R[8] - 1.0)));
    double theta = acos(cos_t);
    if (M_PI - theta < 1e-6) {
        double diag[3] = {0.5 * (R[0] + 1.0), 0.5 * (R[4] + 1.0), 0.5 * (R[8] + 1.0)};
        int j = 0;
        for (int i = 1; i < 3; i++)
            if (diag[i] > diag[j]) j = i;
        double axis[3] = {0.5 * (R[j] + (j == 0 ? 1.0 : 0.0)),
                          0.5 * (R[3 + j] + (j == 1 ? 1.0 : 0.0)),
                          0.5 * (R[6 + j] + (j == 2 ? 1.0 : 0.0))};
        double n = norm3(axis);
        out[0] = theta * axis[0] / n;
        out[1] = theta * axis[1] / n;
        out[2] = theta * axis[2] / n;
        return;
    }
    double k = theta < 1e-9 ? 0.5 : theta / (2.0 * sin(theta));
    out[0] = k * (R[7] - R[5]);
    out[1] = k * (R[2] - R[6]);
    out[2] = k * (R[3] - R[1]);
}

/* CPython's float ** for an exponent of 2.0 (Objects/floatobject.c, float_pow): pow of the
 * absolute value (an even exponent leaves the sign). */
static double py_square(double x) {
    if (x == 0.0 || isnan(x) || isinf(x)) return pow(x, 2.0);
    if (x < 0.0) x = -x;
    if (x == 1.0) return 1.0;
    return pow(x, 2.0);
}

/* ------------------------------------------------------------------------------------------
 * buffers: numpy arrays shared with Python, their data pointers taken once
 * ---------------------------------------------------------------------------------------- */

#define MAX_KEEP 24

typedef struct {
    PyObject* obj[MAX_KEEP];
    int n;
} Keep;

/* The data of a writable C-contiguous float64 buffer of at least ``n`` items (a reference to
 * its owner kept in ``keep``); NULL with an exception set otherwise. */
static double* doubles(PyObject* o, Py_ssize_t n, Keep* keep, const char* what) {
    Py_buffer view;
    if (PyObject_GetBuffer(o, &view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    int ok = view.format && strcmp(view.format, "d") == 0 && view.itemsize == 8
             && view.len >= n * 8;
    double* p = (double*)view.buf;
    PyBuffer_Release(&view);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: a contiguous float64 array of >= %zd items", what, n);
        return NULL;
    }
    if (keep->n >= MAX_KEEP) {
        PyErr_SetString(PyExc_RuntimeError, "too many buffers");
        return NULL;
    }
    Py_INCREF(o);
    keep->obj[keep->n++] = o;
    return p;
}

static void release(Keep* keep) {
    for (int i = 0; i < keep->n; i++) Py_DECREF(keep->obj[i]);
    keep->n = 0;
}

static void* address(PyObject* o) {
    void* p = PyLong_AsVoidPtr(o);
    if (!p && !PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "null MuJoCo address");
    return p;
}

/* The state behind the first of ``n`` fast-call arguments, a capsule named ``name``, where
 * there are ``want`` arguments; NULL with an exception set otherwise. */
static void* state_of(PyObject* const* args, Py_ssize_t n, Py_ssize_t want, const char* name,
                      const char* usage) {
    if (n != want) {
        PyErr_Format(PyExc_TypeError, "usage: %s", usage);
        return NULL;
    }
    return PyCapsule_GetPointer(args[0], name);
}

/* ------------------------------------------------------------------------------------------
 * the arm: F/T sample -> payload compensation -> TCP wrench -> admittance -> IK
 * (control/arm.py, sim/ft_sensor.py, control/admittance.py)
 * ---------------------------------------------------------------------------------------- */

typedef struct {
    const mjModel* m;
    mjData* d;
    mjData* sd;  /* scratch data for the IK */
    int tcp, ft, qpos0, act0, dof0, ftadr, nv;
    double dls_damp, max_joint_speed, gravity;
    int ik_iterations;
    /* shared arrays (see ArmController.__init__ for their layout) */
    double *ref, *offset, *vel, *wdes, *K, *D, *M, *vmax;
    double *filt, *tare, *pay, *wrench, *wsens, *q, *noise, *ftst;
    double* jac;  /* 6 x nv: translation rows, rotation rows */
    double J[36], H[36];
    Keep keep;
} Arm;

/* admittance.Admittance.step on six axes */
static void admittance_step(double* e, double* v, const double* wd, const double* K,
                            const double* D, const double* M, const double* vmax,
                            const double* w, double dt) {
    for (int i = 0; i < 6; i++) {
        double den = D[i] * dt + M[i];
        double vi = (v[i] * M[i] + ((wd[i] - K[i] * e[i]) + w[i]) * dt) / den;
        double vm = vmax[i];
        vi = py_max(py_min(vi, vm), -vm);
        v[i] = vi;
        e[i] = e[i] + vi * dt;
    }
}

/* ArmController._gravity_wrench: pay = (mass, cx, cy, cz, ...) */
static void gravity_wrench(const Arm* a, double* g) {
    double w = -a->gravity * a->pay[0];
    const double* R = a->d->site_xmat + 9 * a->ft;
    double zx = R[6], zy = R[7], zz = R[8];
    double gx = w * zx, gy = w * zy, gz = w * zz;
    double cx = a->pay[1], cy = a->pay[2], cz = a->pay[3];
    g[0] = gx;
    g[1] = gy;
    g[2] = gz;
    g[3] = cy * gz - cz * gy;
    g[4] = cz * gx - cx * gz;
    g[5] = cx * gy - cy * gx;
}

/* FTSensor.sample then ArmController.read_ft */
static void read_ft(Arm* a, int row) {
    const double* raw = a->d->sensordata + a->ftadr;
    const double* noise = a->noise + 6 * row;
    double noisy[6];
    for (int i = 0; i < 6; i++) noisy[i] = noise[i] + raw[i];
    double* y = a->filt;
    if (a->ftst[0] == 0.0) {
        memcpy(y, noisy, sizeof noisy);
        a->ftst[0] = 1.0;
    } else {
        double alpha = a->ftst[1];
        for (int i = 0; i < 6; i++) y[i] += (noisy[i] - y[i]) * alpha;
    }
    double w[6];
    for (int i = 0; i < 6; i++) w[i] = a->tare[i] - y[i];
    if (a->pay[4] != 0.0) {
        double g[6];
        const double* t = a->pay + 5;
        gravity_wrench(a, g);
        for (int i = 0; i < 6; i++) w[i] = (w[i] - g[i]) + t[i];
    }
    memcpy(a->wsens, w, sizeof w);
    const double* R = a->d->site_xmat + 9 * a->ft;
    double f[3], mo[3];
    mv(R, w, f);
    mv(R, w + 3, mo);
    const double* x = a->d->site_xpos + 3 * a->ft;
    const double* y0 = a->d->site_xpos + 3 * a->tcp;
    double r0 = x[0] - y0[0], r1 = x[1] - y0[1], r2 = x[2] - y0[2];
    double* W = a->wrench;
    W[0] = f[0];
    W[1] = f[1];
    W[2] = f[2];
    W[3] = mo[0] + (r1 * f[2] - r2 * f[1]);
    W[4] = mo[1] + (r2 * f[0] - r0 * f[2]);
    W[5] = mo[2] + (r0 * f[1] - r1 * f[0]);
}

/* ArmController._commanded_t: p = p_ref + e_p, R = exp([e_r]_x) R_ref */
static void commanded(const Arm* a, double* p, double* R) {
    const double* e = a->offset;
    p[0] = a->ref[0] + e[0];
    p[1] = a->ref[1] + e[1];
    p[2] = a->ref[2] + e[2];
    if (e[3] == 0.0 && e[4] == 0.0 && e[5] == 0.0) {
        memcpy(R, a->ref + 3, 9 * sizeof(double));
        return;
    }
    double X[9];
    exp_so3(e[3], e[4], e[5], X);
    mm(X, a->ref + 3, R);
}

/* ArmController.update */
static void arm_update(Arm* a, double dt, int row, int compliant) {
    read_ft(a, row);
    if (compliant)
        admittance_step(a->offset, a->vel, a->wdes, a->K, a->D, a->M, a->vmax, a->wrench, dt);
    double p[3], Rc[9];
    commanded(a, p, Rc);
    const mjModel* m = a->m;
    mjData* sd = a->sd;
    double step_max = a->max_joint_speed * dt;
    double* q = a->q;
    double err[6], g[6], dq[6];
    for (int k = 0; k < a->ik_iterations; k++) {
        memcpy(sd->qpos + a->qpos0, q, 6 * sizeof(double));
        mj_kinematics(m, sd);
        if (k == 0) {
            int nv = a->nv;
            mj_comPos(m, sd);
            mj_jacSite(m, sd, a->jac, a->jac + 3 * nv, a->tcp);
            for (int r = 0; r < 6; r++)
                for (int c = 0; c < 6; c++) a->J[6 * r + c] = a->jac[r * nv + a->dof0 + c];
            mju_mulMatTMat(a->H, a->J, a->J, 6, 6, 6);
            for (int i = 0; i < 36; i++) a->H[i] += (i % 7 == 0) ? a->dls_damp : 0.0;
            mju_cholFactor(a->H, 6, 0.0);
        }
        const double* x = sd->site_xpos + 3 * a->tcp;
        double Re[9], r[3];
        mmt(Rc, sd->site_xmat + 9 * a->tcp, Re);
        log_so3(Re, r);
        err[0] = p[0] - x[0];
        err[1] = p[1] - x[1];
        err[2] = p[2] - x[2];
        err[3] = r[0];
        err[4] = r[1];
        err[5] = r[2];
        mju_mulMatTVec(g, a->J, err, 6, 6);
        mju_cholSolve(dq, a->H, g, 6);
        double hi = dq[0], lo = dq[0];
        for (int i = 1; i < 6; i++) {
            hi = py_max(hi, dq[i]);
            lo = py_min(lo, dq[i]);
        }
        if (hi > step_max || lo < -step_max)
            for (int i = 0; i < 6; i++) dq[i] = fmax(fmin(dq[i], step_max), -step_max);
        for (int i = 0; i < 6; i++) q[i] += dq[i];
        double emax = err[0], emin = err[0];
        for (int i = 1; i < 6; i++) {
            emax = py_max(emax, err[i]);
            emin = py_min(emin, err[i]);
        }
        if (emax < 1e-7 && emin > -1e-7) break;
    }
    memcpy(a->d->ctrl + a->act0, q, 6 * sizeof(double));
}

static void arm_free(PyObject* capsule) {
    Arm* a = (Arm*)PyCapsule_GetPointer(capsule, "vgs.arm");
    if (!a) return;
    release(&a->keep);
    free(a->jac);
    free(a);
}

static const char* ARM_ARRAYS[] = {"ref", "offset", "velocity", "wrench_des", "stiffness",
                                   "damping", "mass", "vmax", "filtered", "tare", "payload",
                                   "wrench", "wrench_sensor", "q_cmd", "noise", "ft_state"};
static const Py_ssize_t ARM_SIZES[] = {12, 6, 6, 6, 6, 6, 6, 6, 6, 6, 11, 6, 6, 6, 6, 2};
#define ARM_NARRAYS 16

/* arm_new(model, data, scratch, (tcp, ft, qpos0, act0, dof0, ftadr, ik_iterations),
 *         (dls_damp, max_joint_speed, gravity), arrays) -> capsule */
static PyObject* py_arm_new(PyObject* self, PyObject* args) {
    PyObject *pm, *pd, *ps, *arrays;
    int tcp, ft, qpos0, act0, dof0, ftadr, iterations;
    double damp, speed, gravity;
    if (!PyArg_ParseTuple(args, "OOO(iiiiiii)(ddd)O", &pm, &pd, &ps, &tcp, &ft, &qpos0, &act0,
                          &dof0, &ftadr, &iterations, &damp, &speed, &gravity, &arrays))
        return NULL;
    if (!PyTuple_Check(arrays) || PyTuple_GET_SIZE(arrays) != ARM_NARRAYS) {
        PyErr_Format(PyExc_ValueError, "arm_new needs %d arrays", ARM_NARRAYS);
        return NULL;
    }
    Arm* a = calloc(1, sizeof(Arm));
    if (!a) return PyErr_NoMemory();
    a->m = address(pm);
    a->d = a->m ? address(pd) : NULL;
    a->sd = a->d ? address(ps) : NULL;
    if (!a->sd) {
        free(a);
        return NULL;
    }
    a->tcp = tcp, a->ft = ft, a->qpos0 = qpos0, a->act0 = act0, a->dof0 = dof0;
    a->ftadr = ftadr, a->nv = a->m->nv, a->dls_damp = damp, a->max_joint_speed = speed;
    a->gravity = gravity, a->ik_iterations = iterations;
    double** slots[ARM_NARRAYS] = {&a->ref, &a->offset, &a->vel, &a->wdes, &a->K, &a->D,
                                   &a->M, &a->vmax, &a->filt, &a->tare, &a->pay, &a->wrench,
                                   &a->wsens, &a->q, &a->noise, &a->ftst};
    for (int i = 0; i < ARM_NARRAYS; i++) {
        *slots[i] = doubles(PyTuple_GET_ITEM(arrays, i), ARM_SIZES[i], &a->keep, ARM_ARRAYS[i]);
        if (!*slots[i]) {
            release(&a->keep);
            free(a);
            return NULL;
        }
    }
    a->jac = calloc(6 * (size_t)a->nv, sizeof(double));
    if (!a->jac) {
        release(&a->keep);
        free(a);
        return PyErr_NoMemory();
    }
    PyObject* capsule = PyCapsule_New(a, "vgs.arm", arm_free);
    if (!capsule) {
        release(&a->keep);
        free(a->jac);
        free(a);
    }
    return capsule;
}

/* arm_update(capsule, dt, noise_row, compliant) */
static PyObject* py_arm_update(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Arm* a = state_of(args, n, 4, "vgs.arm", "arm_update(arm, dt, noise_row, compliant)");
    if (!a) return NULL;
    double dt = PyFloat_AsDouble(args[1]);
    long row = PyLong_AsLong(args[2]);
    int compliant = PyObject_IsTrue(args[3]);
    if (PyErr_Occurred() || compliant < 0) return NULL;
    arm_update(a, dt, (int)row, compliant);
    Py_RETURN_NONE;
}

/* arm_commanded(capsule, out): out[0:3] = p_cmd, out[3:12] = R_cmd */
static PyObject* py_arm_commanded(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Arm* a = state_of(args, n, 1, "vgs.arm", "arm_commanded(arm)");
    if (!a) return NULL;
    double p[3], R[9];
    commanded(a, p, R);
    return Py_BuildValue("(ddd)(ddddddddd)", p[0], p[1], p[2], R[0], R[1], R[2], R[3], R[4],
                         R[5], R[6], R[7], R[8]);
}

/* arm_gravity_wrench(capsule) -> the payload's weight wrench, sensor frame */
static PyObject* py_arm_gravity_wrench(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Arm* a = state_of(args, n, 1, "vgs.arm", "arm_gravity_wrench(arm)");
    if (!a) return NULL;
    double g[6];
    gravity_wrench(a, g);
    return Py_BuildValue("(dddddd)", g[0], g[1], g[2], g[3], g[4], g[5]);
}

/* admittance_step(offset, velocity, wrench_des, stiffness, damping, mass, vmax, wrench, dt):
 * Admittance.step outside the arm (the arrays as in arm_new) */
static PyObject* py_admittance_step(PyObject* self, PyObject* args) {
    PyObject* o[8];
    double dt;
    if (!PyArg_ParseTuple(args, "OOOOOOOOd", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5], &o[6],
                          &o[7], &dt))
        return NULL;
    static const char* names[8] = {"offset", "velocity", "wrench_des", "stiffness", "damping",
                                   "mass", "vmax", "wrench"};
    double* p[8];
    Keep keep = {.n = 0};
    for (int i = 0; i < 8; i++) {
        p[i] = doubles(o[i], 6, &keep, names[i]);
        if (!p[i]) {
            release(&keep);
            return NULL;
        }
    }
    admittance_step(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], dt);
    release(&keep);
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------
 * the pads' stick latch (sim/stiction.py)
 * ---------------------------------------------------------------------------------------- */

typedef struct {
    const mjModel* m;
    mjData* d;
    int eq, housing, peg, tcp, peg_geom, left, right, dof;
    double grip, pad_friction, peg_radius, capacity_per_newton;
    double engage_fraction, release_fraction, stick_speed, stick_rate, reengage_load;
    double* out;  /* (last_load, breaks) shared with Python */
    double* weights;
    int nweights;
    double* qfrc;
    Keep keep;
} Latch;

static int grow(Latch* s, int n) {
    if (n <= s->nweights) return 0;
    double* w = realloc(s->weights, (size_t)n * sizeof(double));
    if (!w) return -1;
    s->weights = w;
    s->nweights = n;
    return 0;
}

/* PadStiction._copy_weld_rows: the weld's rows (equality rows come first, each constraint's
 * rows together) */
static void copy_weld_rows(const Latch* s, double* weights) {
    const mjData* d = s->d;
    int ne = d->ne, first = -1, count = 0;
    for (int i = 0; i < ne; i++) {
        if (d->efc_id[i] == s->eq) {
            if (first < 0) first = i;
            count++;
        }
    }
    for (int i = first; i >= 0 && i < first + count; i++) weights[i] = d->efc_force[i];
}

/* PadStiction._select_pad_rows: the pad contacts' and the weld's rows; the pads' normal
 * forces */
static void select_pad_rows(const Latch* s, double* n_left, double* n_right) {
    const mjData* d = s->d;
    int nefc = d->nefc;
    memset(s->weights, 0, (size_t)nefc * sizeof(double));
    double nl = 0.0, nr = 0.0;
    for (int i = 0; i < d->ncon; i++) {
        const mjContact* c = d->contact + i;
        int g0 = c->geom[0], g1 = c->geom[1], side;
        if ((g0 == s->peg_geom && g1 == s->left) || (g0 == s->left && g1 == s->peg_geom))
            side = 0;
        else if ((g0 == s->peg_geom && g1 == s->right) || (g0 == s->right && g1 == s->peg_geom))
            side = 1;
        else
            continue;
        int adr = c->efc_address;
        if (adr < 0) continue;
        for (int j = adr; j < adr + c->dim && j < nefc; j++) s->weights[j] = d->efc_force[j];
        if (side == 0)
            nl += d->efc_force[adr];
        else
            nr += d->efc_force[adr];
    }
    copy_weld_rows(s, s->weights);
    *n_left = nl;
    *n_right = nr;
}

/* PadStiction._selected_wrench: force and moment about the TCP, tool frame */
static void selected_wrench(const Latch* s, double* f_tool, double* m_tool) {
    const mjModel* m = s->m;
    const mjData* d = s->d;
    mj_mulJacTVec(m, d, s->qfrc, s->weights);
    const double* f = s->qfrc + s->dof;
    double t[3];
    mv(d->xmat + 9 * s->peg, s->qfrc + s->dof + 3, t);
    const double* p = d->xpos + 3 * s->peg;
    const double* c = d->site_xpos + 3 * s->tcp;
    double r0 = p[0] - c[0], r1 = p[1] - c[1], r2 = p[2] - c[2];
    double mom[3] = {t[0] + (r1 * f[2] - r2 * f[1]), t[1] + (r2 * f[0] - r0 * f[2]),
                     t[2] + (r0 * f[1] - r1 * f[0])};
    double fw[3] = {f[0], f[1], f[2]};
    const double* R = d->site_xmat + 9 * s->tcp;
    mtv(R, fw, f_tool);
    mtv(R, mom, m_tool);
}

/* PadStiction._limit_value */
static double limit_value(const Latch* s, const double* f, const double* mom, double normal) {
    if (normal <= 0.0) return INFINITY;
    double mu_n = s->pad_friction * normal;
    double m_y = s->capacity_per_newton * normal;
    return sqrt(py_square(f[0] / mu_n) + py_square(f[2] / mu_n)
                + py_square(mom[0] / (mu_n * s->peg_radius)) + py_square(mom[1] / m_y));
}

/* PadStiction._relative_motion_small */
static int relative_motion_small(const Latch* s) {
    const mjModel* m = s->m;
    const mjData* d = s->d;
    double vel[6], hsg[6];
    mj_objectVelocity(m, d, mjOBJ_BODY, s->peg, vel, 0);
    mj_objectVelocity(m, d, mjOBJ_BODY, s->housing, hsg, 0);
    const double* tcp = d->site_xpos + 3 * s->tcp;
    const double* pp = d->xpos + 3 * s->peg;
    const double* ph = d->xpos + 3 * s->housing;
    double a[3] = {tcp[0] - pp[0], tcp[1] - pp[1], tcp[2] - pp[2]};
    double b[3] = {tcp[0] - ph[0], tcp[1] - ph[1], tcp[2] - ph[2]};
    /* v = v_origin + w x (p_tcp - p_origin) */
    double v_peg[3] = {vel[3] + (vel[1] * a[2] - vel[2] * a[1]),
                       vel[4] + (vel[2] * a[0] - vel[0] * a[2]),
                       vel[5] + (vel[0] * a[1] - vel[1] * a[0])};
    double v_hsg[3] = {hsg[3] + (hsg[1] * b[2] - hsg[2] * b[1]),
                       hsg[4] + (hsg[2] * b[0] - hsg[0] * b[2]),
                       hsg[5] + (hsg[0] * b[1] - hsg[1] * b[0])};
    double dv[3] = {v_peg[0] - v_hsg[0], v_peg[1] - v_hsg[1], v_peg[2] - v_hsg[2]};
    double dw[3] = {vel[0] - hsg[0], vel[1] - hsg[1], vel[2] - hsg[2]};
    return norm3(dv) < s->stick_speed && norm3(dw) < s->stick_rate;
}

/* PadStiction._engage: weld the peg to the housing at their present relative pose */
static void engage(Latch* s) {
    const mjModel* m = s->m;
    mjData* d = s->d;
    const double* p1 = d->xpos + 3 * s->housing;
    const double* R1 = d->xmat + 9 * s->housing;
    const double* p2 = d->xpos + 3 * s->peg;
    const double* R2 = d->xmat + 9 * s->peg;
    double* eq = m->eq_data + mjNEQDATA * s->eq;
    double dp[3] = {p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]};
    double rel[3], R[9], q[4];
    mtv(R1, dp, rel);
    mtm(R1, R2, R);
    mju_mat2Quat(q, R);
    eq[0] = eq[1] = eq[2] = 0.0;
    memcpy(eq + 3, rel, sizeof rel);
    memcpy(eq + 6, q, sizeof q);
    eq[10] = 1.0;
    d->eq_active[s->eq] = 1;
}

/* PadStiction.update */
static int latch_update(Latch* s) {
    mjData* d = s->d;
    double grip = s->grip;
    int stuck = d->eq_active[s->eq] != 0;
    if (!stuck && !d->ncon) {
        s->out[0] = 0.0;
        return 0;
    }
    if (grow(s, d->nefc) < 0) return -1;
    double n_left, n_right;
    select_pad_rows(s, &n_left, &n_right);
    if (!stuck && py_min(n_left, n_right) < s->engage_fraction * grip) {
        s->out[0] = 0.0;
        return 0;
    }
    double f[3], mom[3];
    selected_wrench(s, f, mom);
    double load = limit_value(s, f, mom, n_left + n_right);
    s->out[0] = load;
    if (stuck) {
        if (load > 1.0 || n_left + n_right < 2.0 * s->release_fraction * grip) {
            d->eq_active[s->eq] = 0;
            s->out[1] += 1.0;
        }
    } else if (load < s->reengage_load && relative_motion_small(s)) {
        engage(s);
    }
    return 0;
}

static void latch_free(PyObject* capsule) {
    Latch* s = (Latch*)PyCapsule_GetPointer(capsule, "vgs.latch");
    if (!s) return;
    release(&s->keep);
    free(s->weights);
    free(s->qfrc);
    free(s);
}

/* latch_new(model, data, (eq, housing, peg, tcp, peg_geom, left, right, dof),
 *           (grip, pad_friction, peg_radius, capacity_per_newton),
 *           (engage_fraction, release_fraction, stick_speed, stick_rate, reengage_load), out) */
static PyObject* py_latch_new(PyObject* self, PyObject* args) {
    PyObject *pm, *pd, *out;
    Latch* s = calloc(1, sizeof(Latch));
    if (!s) return PyErr_NoMemory();
    if (!PyArg_ParseTuple(args, "OO(iiiiiiii)(dddd)(ddddd)O", &pm, &pd, &s->eq, &s->housing,
                          &s->peg, &s->tcp, &s->peg_geom, &s->left, &s->right, &s->dof,
                          &s->grip, &s->pad_friction, &s->peg_radius, &s->capacity_per_newton,
                          &s->engage_fraction, &s->release_fraction, &s->stick_speed,
                          &s->stick_rate, &s->reengage_load, &out)) {
        free(s);
        return NULL;
    }
    s->m = address(pm);
    s->d = s->m ? address(pd) : NULL;
    s->out = s->d ? doubles(out, 2, &s->keep, "out") : NULL;
    s->qfrc = s->out ? calloc((size_t)s->m->nv, sizeof(double)) : NULL;
    if (!s->qfrc) {
        if (!PyErr_Occurred()) PyErr_NoMemory();
        release(&s->keep);
        free(s);
        return NULL;
    }
    PyObject* capsule = PyCapsule_New(s, "vgs.latch", latch_free);
    if (!capsule) {
        release(&s->keep);
        free(s->qfrc);
        free(s);
    }
    return capsule;
}

static PyObject* py_latch_update(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Latch* s = state_of(args, n, 1, "vgs.latch", "latch_update(latch)");
    if (!s) return NULL;
    if (latch_update(s) < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* PadStiction.weld_wrench: the weld's rows alone */
static int weld_wrench(Latch* s, double* f, double* mom) {
    if (grow(s, s->d->nefc) < 0) return -1;
    memset(s->weights, 0, (size_t)s->d->nefc * sizeof(double));
    copy_weld_rows(s, s->weights);
    selected_wrench(s, f, mom);
    return 0;
}

/* latch_weld_wrench(latch) -> ((fx, fy, fz), (mx, my, mz)) */
static PyObject* py_latch_weld_wrench(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Latch* s = state_of(args, n, 1, "vgs.latch", "latch_weld_wrench(latch)");
    if (!s) return NULL;
    double f[3], mom[3];
    if (weld_wrench(s, f, mom) < 0) return PyErr_NoMemory();
    return Py_BuildValue("(ddd)(ddd)", f[0], f[1], f[2], mom[0], mom[1], mom[2]);
}

/* ------------------------------------------------------------------------------------------
 * the record's grasp watch (assembly/episode.py, GraspWatch._sample)
 * ---------------------------------------------------------------------------------------- */

typedef struct {
    const mjModel* m;
    const mjData* d;
    int peg_body, tcp, peg_geom;
    unsigned char* is_finger; /* per geom */
    Latch* latch;             /* NULL without the stick latch */
    double* out;              /* (turn_deg, peak_moment, axis at the start (3)) */
    PyObject* latch_capsule;
    Keep keep;
} Watch;

/* GraspWatch._relative: the peg's axis in the tool frame, R_world_tcp^T a_world */
static void peg_axis_in_tool(const Watch* w, double* out) {
    const double* Rp = w->d->xmat + 9 * w->peg_body;
    double a[3] = {Rp[2], Rp[5], Rp[8]};
    mtv(w->d->site_xmat + 9 * w->tcp, a, out);
}

/* GraspWatch._sample */
static int watch_sample(Watch* w) {
    const mjModel* m = w->m;
    const mjData* d = w->d;
    double rel[3];
    peg_axis_in_tool(w, rel);
    const double* r0 = w->out + 2;
    double cos_t = rel[0] * r0[0] + rel[1] * r0[1] + rel[2] * r0[2];
    double turn = (180.0 / M_PI) * acos(py_max(-1.0, py_min(1.0, cos_t)));
    w->out[0] = py_max(w->out[0], turn);
    if (d->ncon == 0) return 0;
    int peg = w->peg_geom, any = 0;
    const double* tp = d->site_xpos + 3 * w->tcp;
    const double* Rt = d->site_xmat + 9 * w->tcp;
    double pinch[3] = {Rt[1], Rt[4], Rt[7]};
    double moment = 0.0;
    for (int i = 0; i < d->ncon; i++) {
        const mjContact* c = d->contact + i;
        int g0 = c->geom[0], g1 = c->geom[1];
        if (g0 < 0 || g1 < 0) continue; /* a flex contact: no flex touches the pads here */
        if (!((g0 == peg || g1 == peg) && (w->is_finger[g0] || w->is_finger[g1]))) continue;
        any = 1;
        double fc[6], fw[3], tau[3] = {0.0, 0.0, 0.0};
        mj_contactForce(m, d, i, fc);
        const double* frame = c->frame; /* rows: normal, tangents (world) */
        mtv(frame, fc, fw);             /* the force on geom2, world frame: C^T f_c */
        if (c->dim >= 4) {              /* torsional friction: about the contact normal */
            double t_c = fc[3];
            tau[0] = t_c * frame[0];
            tau[1] = t_c * frame[1];
            tau[2] = t_c * frame[2];
        }
        double sign = g0 == peg ? -1.0 : 1.0;
        double rx = c->pos[0] - tp[0], ry = c->pos[1] - tp[1], rz = c->pos[2] - tp[2];
        double t0 = (ry * fw[2] - rz * fw[1]) + tau[0];
        double t1 = (rz * fw[0] - rx * fw[2]) + tau[1];
        double t2 = (rx * fw[1] - ry * fw[0]) + tau[2];
        moment += sign * (t0 * pinch[0] + t1 * pinch[1] + t2 * pinch[2]);
    }
    if (!any) return 0;
    if (w->latch && w->latch->d->eq_active[w->latch->eq]) {
        /* what the pads' stick state carries beyond their contacts' friction */
        double f[3], mom[3];
        if (weld_wrench(w->latch, f, mom) < 0) return -1;
        moment += mom[1];
    }
    w->out[1] = py_max(w->out[1], fabs(moment));
    return 0;
}

static void watch_destroy(Watch* w) {
    release(&w->keep);
    Py_XDECREF(w->latch_capsule);
    free(w->is_finger);
    free(w);
}

static void watch_free(PyObject* capsule) {
    Watch* w = (Watch*)PyCapsule_GetPointer(capsule, "vgs.watch");
    if (w) watch_destroy(w);
}

/* watch_new(model, data, (peg_body, tcp, peg_geom), is_finger (bytes, one per geom),
 *           latch capsule or None, out) -> capsule; out[2:5] = the axis at the start */
static PyObject* py_watch_new(PyObject* self, PyObject* args) {
    PyObject *pm, *pd, *fingers, *latch, *out;
    Watch* w = calloc(1, sizeof(Watch));
    if (!w) return PyErr_NoMemory();
    if (!PyArg_ParseTuple(args, "OO(iii)SOO", &pm, &pd, &w->peg_body, &w->tcp, &w->peg_geom,
                          &fingers, &latch, &out)) {
        free(w);
        return NULL;
    }
    w->m = address(pm);
    w->d = w->m ? address(pd) : NULL;
    w->out = w->d ? doubles(out, 5, &w->keep, "out") : NULL;
    if (w->out && PyBytes_GET_SIZE(fingers) != w->m->ngeom)
        PyErr_SetString(PyExc_ValueError, "is_finger needs one byte per geom");
    if (w->out && !PyErr_Occurred() && latch != Py_None) {
        w->latch = (Latch*)PyCapsule_GetPointer(latch, "vgs.latch");
        if (w->latch) {
            Py_INCREF(latch);
            w->latch_capsule = latch;
        }
    }
    if (!PyErr_Occurred()) {
        w->is_finger = malloc((size_t)w->m->ngeom + 1);
        if (!w->is_finger) PyErr_NoMemory();
        else memcpy(w->is_finger, PyBytes_AS_STRING(fingers), (size_t)w->m->ngeom);
    }
    if (PyErr_Occurred()) {
        watch_destroy(w);
        return NULL;
    }
    peg_axis_in_tool(w, w->out + 2);
    PyObject* capsule = PyCapsule_New(w, "vgs.watch", watch_free);
    if (!capsule) watch_destroy(w);
    return capsule;
}

static PyObject* py_watch_sample(PyObject* self, PyObject* const* args, Py_ssize_t n) {
    Watch* w = state_of(args, n, 1, "vgs.watch", "watch_sample(watch)");
    if (!w) return NULL;
    if (watch_sample(w) < 0) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------
 * the camera's reprojection (sim/camera.py, RayCastCamera.capture)
 * ---------------------------------------------------------------------------------------- */

/* The data of a C-contiguous buffer of ``n`` items of struct format ``fmt`` (a borrowed view:
 * valid while the caller holds the object); NULL with an exception set otherwise. */
static void* items(PyObject* o, Py_ssize_t n, const char* fmt, Py_ssize_t size,
                   const char* what) {
    Py_buffer view;
    if (PyObject_GetBuffer(o, &view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    int ok = view.format && strcmp(view.format, fmt) == 0 && view.itemsize == size
             && view.len == n * size;
    void* p = view.buf;
    PyBuffer_Release(&view);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: a contiguous array of %zd items '%s'", what, n, fmt);
        return NULL;
    }
    return p;
}

/* heightmap_fill(geomid, dist, vec, normal, rgba, (ox, oy, oz, x0, y0, pixel_size, l0, l1, l2),
 *                size, depth, color): each heightmap cell's highest ray hit (z >= 0) and its
 * Lambert-shaded colour, ties to the later ray; depth and color zero elsewhere. The same as
 * the numpy of sim/camera.py it replaced (points p = v d + o, cell floor((p - x0) / s),
 * shade 0.55 + 0.45 clip(n . l, 0, 1), a stable sort by height whose last write won). */
static PyObject* py_heightmap_fill(PyObject* self, PyObject* args) {
    PyObject *pg, *pd, *pv, *pn, *prgba, *pdepth, *pcolor;
    double ox, oy, oz, x0, y0, ps, l0, l1, l2;
    int size, ngeom;
    Py_ssize_t nray;
    if (!PyArg_ParseTuple(args, "OOOOO(ddddddddd)iinOO", &pg, &pd, &pv, &pn, &prgba, &ox, &oy,
                          &oz, &x0, &y0, &ps, &l0, &l1, &l2, &size, &ngeom, &nray, &pdepth,
                          &pcolor))
        return NULL;
    const int* geomid = items(pg, nray, "i", 4, "geomid");
    const double* dist = geomid ? items(pd, nray, "d", 8, "dist") : NULL;
    const double* vec = dist ? items(pv, 3 * nray, "d", 8, "vec") : NULL;
    const double* normal = vec ? items(pn, 3 * nray, "d", 8, "normal") : NULL;
    const float* rgba = normal ? items(prgba, 4 * (Py_ssize_t)ngeom, "f", 4, "rgba") : NULL;
    Py_ssize_t cells = (Py_ssize_t)size * size;
    double* depth = rgba ? items(pdepth, cells, "d", 8, "depth") : NULL;
    double* color = depth ? items(pcolor, 3 * cells, "d", 8, "color") : NULL;
    if (!color) return NULL;
    unsigned char* set = calloc((size_t)cells, 1);
    if (!set) return PyErr_NoMemory();
    memset(depth, 0, (size_t)cells * sizeof(double));
    memset(color, 0, (size_t)cells * 3 * sizeof(double));
    for (Py_ssize_t i = 0; i < nray; i++) {
        int g = geomid[i];
        if (g < 0 || g >= ngeom) continue;
        const double* v = vec + 3 * i;
        double d = dist[i];
        double px = v[0] * d + ox, py = v[1] * d + oy, pz = v[2] * d + oz;
        double fc = floor((px - x0) / ps), fr = floor((py - y0) / ps);
        if (!(fr >= 0.0 && fr < size && fc >= 0.0 && fc < size)) continue;
        Py_ssize_t cell = (Py_ssize_t)fr * size + (Py_ssize_t)fc;
        double z = pz >= 0.0 ? pz : 0.0;
        if (set[cell] && z < depth[cell]) continue;
        const double* n = normal + 3 * i;
        double lit = n[0] * l0 + n[1] * l1 + n[2] * l2;
        double shade = 0.55 + 0.45 * py_min(py_max(lit, 0.0), 1.0);
        const float* c = rgba + 4 * g;
        set[cell] = 1;
        depth[cell] = z;
        color[3 * cell] = (double)c[0] * shade;
        color[3 * cell + 1] = (double)c[1] * shade;
        color[3 * cell + 2] = (double)c[2] * shade;
    }
    free(set);
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------ */

static PyMethodDef METHODS[] = {
    {"arm_new", py_arm_new, METH_VARARGS, "The arm's per-tick state (control/arm.py)."},
    {"arm_update", (PyCFunction)(void (*)(void))py_arm_update, METH_FASTCALL,
     "One control tick of the arm: F/T -> admittance -> IK -> joint targets."},
    {"arm_commanded", (PyCFunction)(void (*)(void))py_arm_commanded, METH_FASTCALL,
     "The commanded pose (p_cmd, R_cmd) as plain floats."},
    {"arm_gravity_wrench", (PyCFunction)(void (*)(void))py_arm_gravity_wrench, METH_FASTCALL,
     "The payload's weight as an external wrench on the tool, sensor frame."},
    {"admittance_step", py_admittance_step, METH_VARARGS, "Admittance.step on six axes."},
    {"latch_new", py_latch_new, METH_VARARGS, "The pads' stick latch (sim/stiction.py)."},
    {"latch_update", (PyCFunction)(void (*)(void))py_latch_update, METH_FASTCALL,
     "Check the latch after a control tick's physics steps."},
    {"latch_weld_wrench", (PyCFunction)(void (*)(void))py_latch_weld_wrench, METH_FASTCALL,
     "The weld's wrench on the peg about the TCP, tool frame."},
    {"heightmap_fill", py_heightmap_fill, METH_VARARGS,
     "The camera's reprojection of its ray hits onto the heightmap."},
    {"watch_new", py_watch_new, METH_VARARGS, "The record's grasp watch."},
    {"watch_sample", (PyCFunction)(void (*)(void))py_watch_sample, METH_FASTCALL,
     "One sample of the grasp watch: the peg's turn in the pads, the moment about the pinch."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef MODULE = {
    PyModuleDef_HEAD_INIT,
    .m_name = "vgs._native",
    .m_doc = "The per-tick kernels in C (see src/vgs/native.py).",
    .m_size = -1,
    .m_methods = METHODS,
};

PyMODINIT_FUNC PyInit__native(void) { return PyModule_Create(&MODULE); }
