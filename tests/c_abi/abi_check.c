/* Compiled against native/mcdem.h and linked with libmcdem.a by tests/physics/c_abi.rs: if the header and
 * the library drift apart (names, argument lists, struct layouts), this stops compiling, linking
 * or printing the values the Rust side expects. Prints "key value" lines. */
#include <stdio.h>
#include <string.h>
#include "mcdem.h"

static void print_error(const char *key, int32_t code) {
    char buf[256];
    size_t n = mcdem_last_error(buf, sizeof buf);
    printf("%s_code %d\n%s_len %zu\n%s_msg %s\n", key, code, key, n, key, buf);
}

int main(void) {
    printf("sizeof_mc_params %zu\nsizeof_contact_load %zu\nsizeof_body %zu\nsizeof_contact_force %zu\n",
           sizeof(mcdem_mc_params), sizeof(mcdem_contact_load), sizeof(mcdem_body),
           sizeof(mcdem_contact_force));
    printf("version %s\n", mcdem_version());

    mcdem_pair_coeffs c;
    int32_t rc = mcdem_pair_coeffs_new(23.3e3, 0.5, 23.3e3, 0.5, 0.95, 0.03, &c);
    printf("coeffs_rc %d\ne_star %.17g\ng_star %.17g\nbeta %.17g\n", rc, c.e_star, c.g_star, c.beta);

    mcdem_normal_force nf;
    rc = mcdem_hertz_normal(&c, 1e-4, 5e-4, 2e-6, -0.01, &nf);
    printf("normal_rc %d\nnormal_force %.17g\nnormal_kt %.17g\n", rc, nf.force, nf.kt);
    printf("sizeof_pair_coeffs %zu\n", sizeof(mcdem_pair_coeffs));
    /* Filled by hand, without the derived damping ratio: rejected, not silently undamped. */
    mcdem_pair_coeffs hand = {c.e_star, c.g_star, c.beta, c.friction, 0.0};
    print_error("hand_coeffs", mcdem_hertz_normal(&hand, 1e-4, 5e-4, 2e-6, -0.01, &nf));

    mcdem_mc_params p = {1e-3, 23.3e3, 0.5, 0.81, 0.11, MCDEM_CAP_ABS};
    mcdem_contact_load cs[3] = {
        {{0.0, 0.0, -0.95e-3}, 1.2e-3}, {{0.0, 0.0, 0.95e-3}, 1.2e-3}, {{0.95e-3, 0.0, 0.0}, 0.0}};
    double delta[3];
    uint8_t fb[3];
    size_t nfb = 99;
    rc = mcdem_radius_changes(&p, cs, 3, delta, fb, &nfb);
    printf("kernel_rc %d\ndelta0 %.17g\ndelta1 %.17g\ndelta2 %.17g\nfb %d %d %d\nn_fallback %zu\n", rc,
           delta[0], delta[1], delta[2], fb[0], fb[1], fb[2], nfb);

    mcdem_body bi = {{0.0, 0.0, 1.9e-3}, {0.0, 0.01, -0.01}, {1.0, 2.0, 3.0}, 1e-3, 4e-6};
    mcdem_body bj = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 1e-3, 4e-6};
    double shear[3] = {0.0, 0.0, 0.0};
    mcdem_contact_force f;
    rc = mcdem_particle_particle(&c, &bi, &bj, 1e-5, -1e-5, 1e-5, shear, &f);
    printf("pair_rc %d\nforce_z %.17g\nforce_y %.17g\ntorque_x %.17g\nshear_y %.17g\nin_contact %d\n", rc,
           f.force_i[2], f.force_i[1], f.torque_i[0], shear[1], f.in_contact);

    double wp[3] = {0.0, 0.0, 0.0}, wv[3] = {0.0, 0.0, 0.0};
    mcdem_body bw = {{0.0, 0.0, 0.9e-3}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 1e-3, 4e-6};
    double sw[3] = {0.0, 0.0, 0.0};
    rc = mcdem_particle_wall(&c, &bw, wp, wv, 0.0, 1e-5, sw, &f);
    printf("wall_rc %d\nwall_force_z %.17g\n", rc, f.force_i[2]);

    /* The pair batch: lane l is the pair above with its own offsets, and must equal the one-pair
     * call bit for bit; lane 2 overlaps beyond a radius and is flagged, not integrated. */
    printf("sizeof_pair_batch %zu\nlib_pair_batch %zu\n", sizeof(mcdem_pair_batch), mcdem_pair_batch_size());
    static mcdem_pair_batch b; /* static: 64-byte aligned storage without a C11 allocator */
    memset(&b, 0xff, sizeof b);
    const int lanes = 3;
    for (int l = 0; l < lanes; l++) {
        const double zi = l == 2 ? 0.5e-3 : 1.9e-3 - 0.05e-3 * l;
        for (int k = 0; k < 3; k++) {
            b.d[k][l] = (k == 2 ? zi : 0.01e-3 * l) - bj.x[k];
            b.vr[k][l] = bi.v[k] * (1.0 + l) - bj.v[k];
            b.omega_i[k][l] = bi.omega[k];
            b.omega_j[k][l] = bj.omega[k] - l;
            b.shear[k][l] = 1e-6 * (k + l);
        }
        b.radius_i[l] = bi.radius;
        b.radius_j[l] = bj.radius;
        b.dri[l] = 1e-5;
        b.drj[l] = -1e-5 * l;
        b.mass_i[l] = bi.mass;
        b.mass_j[l] = bj.mass;
        b.e_star[l] = c.e_star;
        b.g_star[l] = c.g_star;
        b.beta[l] = c.beta;
        b.friction[l] = l == 1 ? 0.0 : 0.5;
        b.damping_ratio_t_n[l] = c.damping_ratio_t_n;
    }
    rc = mcdem_pair_batch_evaluate(&b, lanes, 1e-5);
    printf("batch_rc %d\nbatch_ok %d %d %d\n", rc, b.ok[0], b.ok[1], b.ok[2]);
    int mismatch = 0;
    for (int l = 0; l < 2; l++) {
        mcdem_body a = bi, o = bj;
        for (int k = 0; k < 3; k++) {
            a.x[k] = b.d[k][l] + bj.x[k];
            a.v[k] = b.vr[k][l] + bj.v[k];
            o.omega[k] = b.omega_j[k][l];
        }
        mcdem_pair_coeffs cl = c;
        cl.friction = b.friction[l];
        double sh[3] = {1e-6 * l, 1e-6 * (1 + l), 1e-6 * (2 + l)};
        mcdem_contact_force one;
        mismatch += mcdem_particle_particle(&cl, &a, &o, b.dri[l], b.drj[l], 1e-5, sh, &one) != MCDEM_OK;
        for (int k = 0; k < 3; k++) {
            mismatch += memcmp(&b.force[k][l], &one.force_i[k], sizeof(double)) != 0;
            mismatch += memcmp(&b.torque_i[k][l], &one.torque_i[k], sizeof(double)) != 0;
            mismatch += memcmp(&b.torque_j[k][l], &one.torque_j[k], sizeof(double)) != 0;
            mismatch += memcmp(&b.shear[k][l], &sh[k], sizeof(double)) != 0;
        }
        mismatch += memcmp(&b.normal[l], &one.normal_force, sizeof(double)) != 0;
    }
    printf("batch_mismatch %d\nbatch_normal0 %.17g\n", mismatch, b.normal[0]);
    print_error("batch_empty", mcdem_pair_batch_evaluate(&b, 0, 1e-5));
    b.damping_ratio_t_n[1] = 0.0;
    print_error("batch_hand", mcdem_pair_batch_evaluate(&b, 2, 1e-5));

    /* Error paths: a message naming the parameter, never a crash. */
    print_error("bad_nu", mcdem_pair_coeffs_new(23.3e3, 0.7, 23.3e3, 0.5, 0.95, 0.03, &c));
    mcdem_mc_params bad = p;
    bad.gamma = -1.0;
    print_error("bad_gamma", mcdem_validate_mc_params(&bad));
    bad = p;
    bad.mpr = -0.1;
    print_error("bad_mpr", mcdem_radius_changes(&bad, cs, 3, delta, fb, NULL));
    bad = p;
    bad.cap = 7;
    print_error("bad_cap", mcdem_validate_mc_params(&bad));
    print_error("null", mcdem_radius_changes(&p, NULL, 3, delta, fb, NULL));
    mcdem_body deep = bw;
    deep.x[2] = 0.1e-3; /* 0.1 mm from the wall with a grown radius: overlap 1.1 r */
    print_error("deep", mcdem_particle_wall(&c, &deep, wp, wv, 0.2e-3, 1e-5, sw, &f));

    /* The model settings: the header's indices are the library's table. */
    for (int k = 0; k <= MCDEM_SETTINGS; k++) {
        const char *name = mcdem_setting_name(k);
        printf("setting%d %s\nsetting%d_default %.17g\n", k, name ? name : "(null)", k, mcdem_setting_default(k));
    }
    printf("setting_indices %d %d %d %d\n", MCDEM_SETTING_MPR_TEST, MCDEM_SETTING_PAIR_RADII,
           MCDEM_SETTING_GEOMETRY_TOLERANCE, MCDEM_SETTING_UPDATE_EVERY);
    double sv = -1.0;
    rc = mcdem_setting_parse(MCDEM_SETTING_MPR_TEST, "signed", &sv);
    printf("setting_parse_rc %d\nsetting_parse_value %.17g\n", rc, sv);
    print_error("setting_bad", mcdem_setting_parse(MCDEM_SETTING_UPDATE_EVERY, "2.5", &sv));
    double pair_s[MCDEM_SETTINGS] = {0.0, 0.0, 0.0, 10.0}, wall_s[MCDEM_SETTINGS] = {0.0, 1.0, 0.0, 5.0};
    uint8_t given_s[MCDEM_SETTINGS] = {0, 1, 0, 1};
    print_error("setting_wall", mcdem_settings_check_wall(wall_s, given_s, pair_s));
    return 0;
}
