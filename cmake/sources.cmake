# The one source list of every C consumer: the FMUs (each FMI version and platform),
# the C tests, the bench drivers, the fuzz targets and the Python package's native
# library.  Paths are relative to fmu/src.

# The algorithms: plain C over plain structs, no FMI types.  Each group is what a
# model's FMU ships in sources/ (the core library holds their union).
set(STO_CORE_OBSERVER
    core/observer_pipeline.c core/observer_scheme.c core/super_twisting.c core/implicit_twisting.c core/noise_adaptive.c core/identifier.c
    core/information_identifier.c core/block_scores.c core/input_cadence.c core/gains.c
    core/tuning.c)
set(STO_CORE_ROBOT
    core/robot_pipeline.c core/robot_observer.c core/fixed_lag.c core/rigid_body.c
    core/regressor_identifier.c
    core/statistics_job.c core/input_cadence.c core/gains.c core/tuning.c)
# A model file's regressor as data (harness/model/program.py writes it).
set(STO_CORE_MODEL core/model_pipeline.c core/fixed_lag.c core/term_program.c core/small_solve.c
    core/box_projection.c core/model_damping.c
    core/observer_scheme.c
    core/super_twisting.c core/implicit_twisting.c core/noise_adaptive.c
    core/regressor_identifier.c core/statistics_job.c core/input_cadence.c core/gains.c
    core/tuning.c)
# A model file's equations simulated (identify's scores and refinement; in no FMU).
set(STO_CORE_SIMULATION core/model_simulation.c core/term_program.c core/small_solve.c)
set(STO_CORE_SOURCES ${STO_CORE_OBSERVER} ${STO_CORE_ROBOT} ${STO_CORE_MODEL}
    ${STO_CORE_SIMULATION})
list(REMOVE_DUPLICATES STO_CORE_SOURCES)

# The model-independent instance core under every FMI version.
set(STO_INSTANCE_SOURCES instance/instance.c instance/instance_log.c instance/instance_variables.c
    instance/instance_states.c)
# Headers every FMU ships beside its sources (fmpy compile rebuilds from them).
set(STO_SHIPPED_HEADERS instance/instance.h instance/instance_internal.h instance/model_interface.h
    instance/state_format.h models/state_fields.h models/input_cadence_outputs.h
    models/fixed_lag_outputs.h)

# The FMUs: model identifier, its model file, its core group, the folder of its
# committed modelDescription.xml (FMI 2; FMI 3 in <folder>/fmi3/) and the files of
# its resources/ folder (optional), relative to the repository.  Each model is a
# folder, models/<identifier>/ (its C, descriptions and resources); the observer's
# descriptions stay at fmu/ where the project's contract puts them.
set(STO_MODELS SuperTwistingObserver Pendulum TwistingController RobotObserver ModelObserver)
set(STO_SuperTwistingObserver_MODEL models/SuperTwistingObserver/model.c)
set(STO_SuperTwistingObserver_CORE ${STO_CORE_OBSERVER})
set(STO_SuperTwistingObserver_XML_DIR fmu)
set(STO_Pendulum_MODEL models/Pendulum/model.c)
set(STO_Pendulum_CORE "")
set(STO_Pendulum_XML_DIR fmu/src/models/Pendulum)
set(STO_TwistingController_MODEL models/TwistingController/model.c)
set(STO_TwistingController_CORE "")
set(STO_TwistingController_XML_DIR fmu/src/models/TwistingController)
set(STO_RobotObserver_MODEL models/RobotObserver/model.c)
set(STO_RobotObserver_CORE ${STO_CORE_ROBOT})
set(STO_RobotObserver_XML_DIR fmu/src/models/RobotObserver)
set(STO_ModelObserver_MODEL models/ModelObserver/model.c)
set(STO_ModelObserver_CORE ${STO_CORE_MODEL})
set(STO_ModelObserver_XML_DIR fmu/src/models/ModelObserver)
set(STO_ModelObserver_RESOURCES fmu/src/models/ModelObserver/resources/model.txt)

# The Python package's native library (ctypes): the master loop and the robot batch
# entry points over the same core.
set(STO_NATIVE_SOURCES native/master_loop.c native/robot_native.c native/model_native.c)
