/*
 * mcdem C ABI: the multi-contact contact physics of mcdem (Rust), for the LIGGGHTS shim and any
 * other C/C++ caller. Link with the static library built by `cargo build --release`
 * (target/release/libmcdem.a) plus -lpthread -ldl -lm.
 *
 * Conventions: SI units; every function returns MCDEM_OK (0) or an error code, and
 * mcdem_last_error() gives the message of the last failure on this thread. No function aborts
 * or unwinds into the caller.
 */
#ifndef MCDEM_H
#define MCDEM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MCDEM_OK 0
#define MCDEM_ERR_NULL 1        /* a required pointer was null */
#define MCDEM_ERR_PARAMETER 2   /* a parameter is out of range; the message names it */
#define MCDEM_ERR_NON_FINITE 3  /* an input or result is NaN or infinite */
#define MCDEM_ERR_OVERLAP 4     /* the overlap reached a particle radius */
#define MCDEM_ERR_COINCIDENT 5  /* coincident centres: no contact normal */
#define MCDEM_ERR_INTERNAL 6    /* internal error (a bug: please report) */

#define MCDEM_CAP_NONE 0   /* standard MC (Brodu et al. 2015, Eq. 2) */
#define MCDEM_CAP_ABS 1    /* advanced MC, |delta_k->c| > MPR r trips (default) */
#define MCDEM_CAP_SIGNED 2 /* advanced MC, delta_k->c > MPR r trips (App. A literal) */

/* Particle-side parameters of the multi-contact kernel. */
typedef struct mcdem_mc_params {
    double radius;         /* original radius r_i [m] */
    double youngs_modulus; /* particle's own E [Pa] */
    double poisson_ratio;  /* particle's own nu, in [0, 0.5] */
    double gamma;          /* geometric prefactor, >= 0 */
    double mpr;            /* maximum penetration ratio, >= 0 (read when cap != NONE) */
    int32_t cap;           /* MCDEM_CAP_* */
} mcdem_mc_params;

/* One contact of a particle. */
typedef struct mcdem_contact_load {
    double point[3]; /* contact point relative to the particle centre [m] */
    double force;    /* normal force magnitude at the previous step [N] */
} mcdem_contact_load;

/* Pair coefficients (App. C). */
typedef struct mcdem_pair_coeffs {
    double e_star;   /* effective Young's modulus [Pa] */
    double g_star;   /* effective shear modulus [Pa] */
    double beta;     /* ln e / sqrt(ln^2 e + pi^2) */
    double friction; /* Coulomb coefficient */
    double damping_ratio_t_n; /* sqrt(4 G* / E*), derived; a struct not filled by
                                 mcdem_pair_coeffs_new is rejected */
} mcdem_pair_coeffs;

/* Output of the Hertz normal sub-model. */
typedef struct mcdem_normal_force {
    double force;   /* k_n delta - gamma_n v_n [N] */
    double elastic; /* k_n delta [N] */
    double kn;      /* [N/m] */
    double kt;      /* [N/m] */
    double gamma_n; /* [kg/s] */
    double gamma_t; /* [kg/s] */
} mcdem_normal_force;

/* Kinematic state of a body. */
typedef struct mcdem_body {
    double x[3];
    double v[3];
    double omega[3];
    double radius; /* original radius [m] */
    double mass;   /* [kg] */
} mcdem_body;

/* Result of a contact force evaluation. */
typedef struct mcdem_contact_force {
    double force_i[3];  /* force on i [N]; on j it is the negative */
    double torque_i[3]; /* [N m] */
    double torque_j[3]; /* [N m]; zero for walls */
    double en[3];       /* unit normal from j (or wall) to i */
    double point[3];    /* contact point [m] */
    double overlap;     /* effective overlap [m] */
    double normal_force;/* signed normal force [N] */
    int32_t in_contact; /* 1 in contact, 0 otherwise (everything else zero) */
} mcdem_contact_force;

/* Validates one particle type's parameters (call once at setup). */
int32_t mcdem_validate_mc_params(const mcdem_mc_params *params);

/* Radius change delta[c] [m] at each of the n contacts (Eq. 2, Eq. 3 cap when params->cap != NONE);
 * hertz_fallback[c] = 1 where the cap switched contact c back to Hertz. n_fallback may be null. */
int32_t mcdem_radius_changes(const mcdem_mc_params *params, const mcdem_contact_load *contacts,
                             size_t n, double *delta, uint8_t *hertz_fallback, size_t *n_fallback);

/* Geometry tolerance (model setting geometryTolerance; mcdem run --mc-geometry-tolerance): a store
 * of influence matrices (Eq. 2 without the forces), one per slot. A slot's matrix is reused while the
 * parameters and the number of contacts are the same and every point is within tolerance * radius of
 * the point it was computed from; otherwise it is recomputed. tolerance = 0 is the exact kernel. */
typedef struct mcdem_influence_cache mcdem_influence_cache;

/* New store; NULL when tolerance is not finite and >= 0 (reason in mcdem_last_error). */
mcdem_influence_cache *mcdem_influence_cache_new(double tolerance);

/* Frees a store (NULL is ignored). */
void mcdem_influence_cache_free(mcdem_influence_cache *cache);

/* Matrices recomputed so far. */
uint64_t mcdem_influence_cache_recomputed(const mcdem_influence_cache *cache);

/* mcdem_radius_changes through the matrix kept in `slot` (any stable per-particle number). */
int32_t mcdem_radius_changes_cached(mcdem_influence_cache *cache, size_t slot, const mcdem_mc_params *params,
                                    const mcdem_contact_load *contacts, size_t n, double *delta,
                                    uint8_t *hertz_fallback, size_t *n_fallback);

/* Pair coefficients from two materials, restitution e in (0, 1] and friction mu >= 0. */
int32_t mcdem_pair_coeffs_new(double youngs_i, double poisson_i, double youngs_j, double poisson_j,
                              double restitution, double friction, mcdem_pair_coeffs *out);

/* Hertz normal sub-model for overlap delta [m] (<= 0 gives zero), effective radius and mass,
 * normal relative velocity vn = (v_i - v_j).n [m/s]. */
int32_t mcdem_hertz_normal(const mcdem_pair_coeffs *coeffs, double delta, double reff, double meff,
                           double vn, mcdem_normal_force *out);

/* Particle-particle force with radius changes dri, drj [m]; shear[3] is the tangential history. */
int32_t mcdem_particle_particle(const mcdem_pair_coeffs *coeffs, const mcdem_body *bi,
                                const mcdem_body *bj, double dri, double drj, double dt,
                                double *shear, mcdem_contact_force *out);

/* MCDEM_ERR_OVERLAP (message: where the contact law ends) when overlap [m] reached rmin [m], the
 * smaller original radius of the two bodies (the particle's own for a wall); else MCDEM_OK. */
int32_t mcdem_check_overlap(double overlap, double rmin);

/* A batch of overlapping particle pairs, one pair per lane, in structure-of-arrays form: the
 * library's own layout (64-byte aligned; check sizeof against mcdem_pair_batch_size() once). Fill
 * the inputs of lanes 0..used-1 and call mcdem_pair_batch_evaluate; tangential model `history`. */
#define MCDEM_BATCH_LANES 8
typedef struct mcdem_pair_batch {
    /* inputs */
    __attribute__((aligned(64))) double d[3][MCDEM_BATCH_LANES]; /* x_i - x_j [m] */
    double vr[3][MCDEM_BATCH_LANES];      /* v_i - v_j [m/s] */
    double omega_i[3][MCDEM_BATCH_LANES]; /* [rad/s] */
    double omega_j[3][MCDEM_BATCH_LANES];
    double radius_i[MCDEM_BATCH_LANES];   /* original radii [m] */
    double radius_j[MCDEM_BATCH_LANES];
    double dri[MCDEM_BATCH_LANES];        /* multi-contact radius changes [m] */
    double drj[MCDEM_BATCH_LANES];
    double mass_i[MCDEM_BATCH_LANES];     /* [kg] */
    double mass_j[MCDEM_BATCH_LANES];
    /* the pair's mcdem_pair_coeffs, field by field */
    double e_star[MCDEM_BATCH_LANES];
    double g_star[MCDEM_BATCH_LANES];
    double beta[MCDEM_BATCH_LANES];
    double friction[MCDEM_BATCH_LANES];
    double damping_ratio_t_n[MCDEM_BATCH_LANES];
    double shear[3][MCDEM_BATCH_LANES];   /* tangential history [m], updated in place */
    /* outputs */
    double force[3][MCDEM_BATCH_LANES];    /* force on i [N]; on j it is the negative */
    double torque_i[3][MCDEM_BATCH_LANES]; /* [N m] */
    double torque_j[3][MCDEM_BATCH_LANES]; /* [N m] */
    double fnorm[MCDEM_BATCH_LANES];       /* |force . n| [N] */
    double normal[MCDEM_BATCH_LANES];      /* signed normal force k_n delta - gamma_n v_n [N] */
    uint8_t ok[MCDEM_BATCH_LANES];         /* 1: integrated; 0: ask mcdem_particle_particle why not */
} mcdem_pair_batch;

/* sizeof(mcdem_pair_batch) as the library lays it out. */
size_t mcdem_pair_batch_size(void);

/* Lanes 0..used-1 (1 <= used <= MCDEM_BATCH_LANES) of a batch: for each, what
 * mcdem_particle_particle gives for that pair, bit for bit (its point and overlap aside). */
int32_t mcdem_pair_batch_evaluate(mcdem_pair_batch *batch, size_t used, double dt);

/* Particle-wall force; wall_point[3] is the closest wall point, wall_velocity[3] its velocity. */
int32_t mcdem_particle_wall(const mcdem_pair_coeffs *coeffs, const mcdem_body *bi,
                            const double *wall_point, const double *wall_velocity, double dri,
                            double dt, double *shear, mcdem_contact_force *out);

/* The settings of `model mc_advanced` on a deck line, one table for both engines
 * (src/physics/mc_settings.rs): names, defaults, strict parsing and the wall/pair agreement all
 * live in the library. Values are one double per setting (a choice as 0 or 1). */
#define MCDEM_SETTING_MPR_TEST 0           /* mprTest abs|signed (0 abs, 1 signed) */
#define MCDEM_SETTING_PAIR_RADII 1         /* pairRadii modified|stock (0 modified, 1 stock) */
#define MCDEM_SETTING_GEOMETRY_TOLERANCE 2 /* geometryTolerance TOL, a number >= 0 */
#define MCDEM_SETTING_UPDATE_EVERY 3       /* updateEvery K, a whole number 1 .. 1e9 */
#define MCDEM_SETTINGS 4

/* Keyword of setting k (static string); NULL when k is not a setting. */
const char *mcdem_setting_name(int32_t k);

/* Keyword k of model mc_advanced that only `mcdem run` implements (the accuracy budget; static
 * string); NULL past the last one. The plugin refuses these with mcdem_engine_only_why(). */
const char *mcdem_engine_only_setting(int32_t k);

/* Why the plugin refuses the keywords of mcdem_engine_only_setting (static string). */
const char *mcdem_engine_only_why(void);

/* Value of setting k when the line does not give it (NaN when k is not a setting). */
double mcdem_setting_default(int32_t k);

/* Reads the word after keyword k into *value; MCDEM_ERR_PARAMETER with a message naming the
 * keyword, the word and what is expected. */
int32_t mcdem_setting_parse(int32_t k, const char *word, double *value);

/* A wall's settings (wall[], given[k] != 0 when its line gave setting k) against the pair
 * style's (pair[]), MCDEM_SETTINGS entries each: MCDEM_ERR_PARAMETER naming the first setting a
 * wall may only repeat and gives with another value. */
int32_t mcdem_settings_check_wall(const double *wall, const uint8_t *given, const double *pair);

/* The material table of n atom types (walls are atom types too): per type E [Pa], nu, gamma and
 * MPR with cap (MCDEM_CAP_ABS or MCDEM_CAP_SIGNED) into params[n] (radius 1: set each particle's
 * own at each call), and the pair coefficients of every ordered type pair from the
 * peratomtypepair tables restitution[n*n] and friction[n*n] (NULL: frictionless) into
 * coeffs[n*n], row-major. MCDEM_ERR_PARAMETER names the LIGGGHTS property and the atom type(s). */
int32_t mcdem_material_table(size_t n, const double *youngs, const double *poisson, const double *gamma,
                             const double *mpr, int32_t cap, const double *restitution,
                             const double *friction, mcdem_mc_params *params, mcdem_pair_coeffs *coeffs);

/* Copies the last error message (NUL-terminated, truncated to len); returns its full length. */
size_t mcdem_last_error(char *buf, size_t len);

/* Library version string. */
const char *mcdem_version(void);

#ifdef __cplusplus
}
#endif

#endif /* MCDEM_H */
