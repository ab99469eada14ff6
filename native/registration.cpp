/*
 * Registration of `model mc_advanced` with LIGGGHTS's factories at static initialisation, and the
 * entry point of the `mcdem-liggghts` executable.
 */
#include "pair_loop.h"

namespace {

template <typename T>
PairStyles::IGranularPairStyle *make_pair(LAMMPS *lmp, PairGran *parent, const int64_t hash) {
    return new T(lmp, parent, hash);
}

template <typename T>
Walls::IGranularWall *make_wall(LAMMPS *lmp, FixWallGran *parent, const int64_t hash) {
    return new T(lmp, parent, hash);
}

// One optimised instance per combination a deck may select; an unregistered combination would
// fall back to the library's runtime dispatch, which does not know mc_advanced.
template <int TANGENTIAL>
void register_combination() {
    typedef GranStyle<MC_ADVANCED, TANGENTIAL, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> Style;
    typedef ContactModel<Style> Model;
    PairStyles::Factory::instance().addStyle("gran", Style::HASHCODE, &make_pair<PairStyles::Granular<Model> >);
    Walls::Factory::instance().addStyle("gran", Style::HASHCODE, &make_wall<Walls::Granular<Model> >);
}

struct Registrar {
    Registrar() {
        ContactModels::Factory::instance().addNormalModel("mc_advanced", MC_ADVANCED);
        register_combination<TANGENTIAL_NO_HISTORY>();
        register_combination<TANGENTIAL_HISTORY>();
    }
};

Registrar registrar;

}  // namespace

// Entry point of `mcdem-liggghts`: the stock LIGGGHTS command line (-in, -var, -log, -echo, ...)
// with mc_advanced registered. Referencing this function from the executable also keeps the
// registrar's object file in the link.
extern "C" int mcdem_liggghts_main(int argc, char **argv) {
    // A run stopped by one rank (error->one: a contact out of range) ends in MPI_Abort, which
    // discards what stdio still buffers; with stdout going to a file or pipe the ERROR line itself
    // would be lost. Line buffering writes each line as it is completed (the screen output is a
    // few lines per thousand steps, so this costs nothing measurable).
    std::setvbuf(stdout, NULL, _IOLBF, 0);
    MPI_Init(&argc, &argv);
    LAMMPS_NS::LAMMPS *lmp = new LAMMPS_NS::LAMMPS(argc, argv, MPI_COMM_WORLD);
    lmp->input->file();
    delete lmp;
    MPI_Finalize();
    return 0;
}
