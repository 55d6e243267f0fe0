// libsystemc's own main() calls sc_main, and the shared library does not
// link without one; motionctl and the tests have their own main() and run
// their models with sc_start(). sim/CMakeLists.txt links this object into
// every user of mc_sim, since a static archive member nobody calls is never
// pulled in. SystemC declares it extern "C".
extern "C" int sc_main(int, char**) {
  return 1;
}
