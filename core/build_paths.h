#pragma once
// Absolute paths of the build that compiled a target (the csw binary, the
// dlopen'ed modules, the source tree, ../shared/data), for the code that needs
// them: each macro below (CSW_BINARY, ...) is defined, only in the targets
// that ask for it with csw_path_constants() (cmake/CswHelpers.cmake), as the
// name of one of these constants, whose value is compiled in one small
// generated file. Passing the paths as -D definitions instead made every file
// of those targets miss the compiler cache in each fresh checkout.

namespace csw::build_paths {

extern const char path_csw_binary[];                   // CSW_BINARY
extern const char path_csw_figures_module_file[];      // CSW_FIGURES_MODULE_FILE
extern const char path_csw_figures_module_path[];      // CSW_FIGURES_MODULE_PATH
extern const char path_csw_video_module_path[];        // CSW_VIDEO_MODULE_PATH
extern const char path_csw_source_dir_default[];       // CSW_SOURCE_DIR_DEFAULT
extern const char path_csw_shared_data_default[];      // CSW_SHARED_DATA_DEFAULT
extern const char path_csw_c3d_default_shared_data[];  // CSW_C3D_DEFAULT_SHARED_DATA
extern const char path_csw_synth_source_dir[];         // CSW_SYNTH_SOURCE_DIR
extern const char path_csw_label_kill_child[];         // CSW_LABEL_KILL_CHILD
extern const char path_csw_source_dir[];               // CSW_SOURCE_DIR
extern const char path_csw_demo_source_dir[];          // CSW_DEMO_SOURCE_DIR

}  // namespace csw::build_paths
