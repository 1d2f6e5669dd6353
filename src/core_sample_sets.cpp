// The compiled copy of the sample sets' definitions in s2kf/core/ (the LCD optimiser), and of the
// marginal update (core/compilation_mode.hpp).
#include <s2kf/core/lcd_distance.hxx>
#include <s2kf/core/lcd_sample_set.hxx>
#include <s2kf/core/marginal_update.hxx>
#include <s2kf/core/sample_set.hxx>
