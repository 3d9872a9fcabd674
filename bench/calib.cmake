impactdic_add_benchmark(NAME calib_benchmark SOURCES calib_benchmark.cc
                        DEPS impactdic::calib impactdic::preprocess impactdic::synth)
