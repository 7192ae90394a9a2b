/* Calls nav-ffi from C on the firmware tests' inputs (MLP, ZUPT, TCZUPT, GNSS/INS, all f32 with
   the INS position in double) and prints every output in the firmware's line protocol; the
   comparison with the host reference (bit for bit) is done by crates/nav-firmware/check.py.
   It also checks, itself, that bad calls come back as error codes. Exit status 1 on failure. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <math.h>

#include "nav_ffi.h"
#include "inputs.h" /* written by check.py from crates/nav-firmware/src/inputs.rs */

#define N (sizeof(STATIC_TEMP) / sizeof(STATIC_TEMP[0]))
#define EVERY 30

static int failures = 0;

static void v(double x) {
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    printf("v %016" PRIx64 "\n", bits);
}

static void v3(const float *x) {
    for (int i = 0; i < 3; i++) v(x[i]);
}

#define CHECK(call)                                                                 \
    do {                                                                            \
        UasnavStatus s_ = (call);                                                   \
        if (s_ != UASNAV_STATUS_OK) {                                               \
            fprintf(stderr, "error: %s returned %d (line %d)\n", #call, (int)s_, __LINE__); \
            return 1;                                                               \
        }                                                                           \
    } while (0)

#define EXPECT(call, want)                                                          \
    do {                                                                            \
        UasnavStatus s_ = (call);                                                   \
        if (s_ != (want)) {                                                         \
            fprintf(stderr, "error: %s returned %d, expected %s\n", #call, (int)s_, #want); \
            failures++;                                                             \
        }                                                                           \
    } while (0)

static void f3(const double *in, float *out) {
    for (int i = 0; i < 3; i++) out[i] = (float)in[i];
}

static void zupt_outputs(UasnavZupt *z) {
    UasnavZuptState s;
    if (uasnav_zupt_state(z, &s) != UASNAV_STATUS_OK) failures++;
    v3(s.position_m);
    v3(s.velocity_m_s);
    for (int i = 0; i < 4; i++) v(s.attitude[i]);
    v3(s.accel_bias_m_s2);
    v3(s.gyro_bias_rad_s);
    for (int i = 0; i < 15; i++) v(s.covariance_diag[i]);
}

static void ins_outputs(UasnavIns *f) {
    UasnavInsState s;
    if (uasnav_ins_state(f, &s) != UASNAV_STATUS_OK) failures++;
    for (int i = 0; i < 3; i++) v(s.llh[i]);
    v3(s.velocity_m_s);
    for (int i = 0; i < 4; i++) v(s.attitude[i]);
    v3(s.accel_bias_m_s2);
    v3(s.gyro_bias_rad_s);
    for (int i = 0; i < 15; i++) v(s.covariance_diag[i]);
}

/* Caller-owned objects: static storage, nothing allocated. */
static UasnavMlp mlp;
static UasnavZupt zupt;
static UasnavIns ins;

static int make_mlp(void) {
    float w1[6], b1[6], w2[36], b2[6], w3[6], norm[4], range[2] = {-40.0f, 85.0f};
    for (int i = 0; i < 6; i++) {
        w1[i] = (float)MLP_W1[i];
        b1[i] = (float)MLP_B1[i];
        b2[i] = (float)MLP_B2[i];
        w3[i] = (float)MLP_W3[i];
    }
    for (int i = 0; i < 36; i++) w2[i] = (float)MLP_W2[i];
    for (int i = 0; i < 4; i++) norm[i] = (float)MLP_NORM[i + 1];
    CHECK(uasnav_mlp_init(&mlp, 6, 6, w1, b1, w2, b2, w3, (float)MLP_NORM[0], norm, range));
    return 0;
}

int main(void) {
    float g[3], a[3], q0[4];
    printf("precision f32\n");

    /* MLP value and dy/dT. */
    if (make_mlp()) return 1;
    printf("case mlp\n");
    for (size_t k = 0; k < N; k += EVERY) {
        float y, dy;
        CHECK(uasnav_mlp_eval(&mlp, (float)STATIC_TEMP[k], false, &y, &dy));
        v((double)k);
        v(y);
        v(dy);
    }
    printf("end\n");

    /* ZUPT: predict every sample, update every 10th. */
    UasnavZuptConfig zc;
    CHECK(uasnav_zupt_config_default(&zc, false));
    CHECK(uasnav_quat_from_euler321((float)0.02, (float)-0.01, (float)0.5, &q0));
    CHECK(uasnav_zupt_init(&zupt, &zc, q0, NULL, NULL, (float)0.01));
    printf("case zupt\n");
    for (size_t k = 0; k < N; k++) {
        f3(STATIC_GYRO[k], g);
        f3(STATIC_ACCEL[k], a);
        CHECK(uasnav_zupt_predict(&zupt, g, a, NULL));
        if ((k + 1) % 10 == 0) CHECK(uasnav_zupt_update(&zupt));
        if ((k + 1) % EVERY == 0) {
            UasnavZuptState s;
            CHECK(uasnav_zupt_state(&zupt, &s));
            v((double)k);
            zupt_outputs(&zupt);
            v(s.last_nis);
        }
    }
    printf("end\n");

    /* TCZUPT: the filter's own step with the MLP's dT-derivative, 1 s slope window. */
    CHECK(uasnav_zupt_config_default(&zc, true));
    zc.temp_slope_window_s = 1.0f;
    CHECK(uasnav_zupt_init(&zupt, &zc, q0, NULL, NULL, (float)0.01));
    const float scale[3] = {(float)1.0, (float)-0.6, (float)0.8};
    printf("case tczupt\n");
    for (size_t k = 0; k < N; k++) {
        bool updated;
        f3(STATIC_GYRO[k], g);
        f3(STATIC_ACCEL[k], a);
        CHECK(uasnav_zupt_step(&zupt, g, a, (float)STATIC_TEMP[k], true, &mlp, scale, &updated));
        if ((k + 1) % EVERY == 0) {
            UasnavZuptState s;
            CHECK(uasnav_zupt_state(&zupt, &s));
            v((double)k);
            zupt_outputs(&zupt);
            v(s.temp_rate_c_s);
        }
    }
    printf("end\n");

    /* GNSS/INS: predict every IMU sample, update at each fix. */
    UasnavInsConfig ic;
    CHECK(uasnav_ins_config_default(&ic));
    CHECK(uasnav_quat_from_euler321((float)FLIGHT_EULER0[0], (float)FLIGHT_EULER0[1], (float)FLIGHT_EULER0[2], &q0));
    float vel0[3], spos[3] = {1.5f, 1.5f, 2.5f}, svel[3] = {0.15f, 0.15f, 0.15f};
    f3(FLIGHT_VEL0, vel0);
    CHECK(uasnav_ins_init(&ins, &ic, FLIGHT_LLH0, vel0, q0, spos, svel));
    printf("case ins\n");
    size_t fix = 0, n_fix = sizeof(GNSS_FIXES) / sizeof(GNSS_FIXES[0]);
    for (size_t k = 0; k < N; k++) {
        f3(FLIGHT_GYRO[k], g);
        f3(FLIGHT_ACCEL[k], a);
        CHECK(uasnav_ins_predict(&ins, g, a, (float)0.01, NULL));
        while (fix < n_fix && (size_t)GNSS_FIXES[fix][0] <= k) {
            const double *f = GNSS_FIXES[fix];
            double llh[3] = {f[1], f[2], f[3]};
            float vel[3], acc[3];
            f3(f + 4, vel);
            f3(f + 7, acc);
            uint8_t st;
            CHECK(uasnav_ins_update_gnss(&ins, llh, vel, acc, 0.0, &st));
            v((double)k);
            v((double)st);
            ins_outputs(&ins);
            fix++;
        }
        if ((k + 1) % EVERY == 0) {
            v((double)k);
            v(-1.0);
            ins_outputs(&ins);
        }
    }
    printf("end\n");

    /* Bad calls: error codes, objects unchanged or refused. */
    static UasnavZupt fresh; /* zeroed: never initialised */
    float nan3[3] = {NAN, 0.0f, 0.0f};
    EXPECT(uasnav_zupt_update(&fresh), UASNAV_STATUS_NOT_INITIALISED);
    EXPECT(uasnav_zupt_predict(NULL, g, a, NULL), UASNAV_STATUS_NULL_POINTER);
    EXPECT(uasnav_zupt_predict(&zupt, NULL, a, NULL), UASNAV_STATUS_NULL_POINTER);
    EXPECT(uasnav_zupt_predict(&zupt, nan3, a, NULL), UASNAV_STATUS_NON_FINITE);
    EXPECT(uasnav_zupt_init(&fresh, &zc, q0, NULL, NULL, -1.0f), UASNAV_STATUS_INVALID_PARAMETER);
    EXPECT(uasnav_zupt_update(&fresh), UASNAV_STATUS_NOT_INITIALISED);
    EXPECT(uasnav_ins_predict(&ins, g, a, 0.0f, NULL), UASNAV_STATUS_INVALID_PARAMETER);
    EXPECT(uasnav_mlp_eval(&mlp, NAN, true, NULL, NULL), UASNAV_STATUS_NON_FINITE);
    EXPECT(uasnav_mlp_init(&mlp, 17, 0, g, g, NULL, NULL, g, 0.0f, q0, g), UASNAV_STATUS_INVALID_PARAMETER);
    EXPECT(uasnav_mlp_eval(&mlp, 20.0f, true, NULL, NULL), UASNAV_STATUS_NOT_INITIALISED);
    EXPECT(uasnav_zupt_step(&zupt, g, a, 20.0f, true, &mlp, scale, NULL), UASNAV_STATUS_NOT_INITIALISED);
    if (failures) {
        fprintf(stderr, "error: %d C interface checks failed\n", failures);
        return 1;
    }
    printf("done\n");
    return 0;
}
