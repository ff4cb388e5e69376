"""The root of every error particlebot raises, so that a script can catch them all at once.

Each error also keeps the built-in class callers caught before the root existed (ValueError for
bad input, RuntimeError, OSError), shown in brackets; indentation shows subclasses.

ParticlebotError
 +-- AnimationError (RuntimeError)        analysis.animation
 +-- GeometryError (ValueError)           analysis.geometry
 +-- SourceError (ValueError)             analysis.sources
 +-- TrackFormatError (ValueError)        analysis.trackfile
 +-- CalibrationError (ValueError)        calibration.photocells
 +-- NobodyAnswers                        calibration.prompts
 +-- Quit                                 calibration.prompts
 +-- ReadingsError (ValueError)           calibration.readings
 +-- UsageError (ValueError)              commands.flash
 +-- CommandError (ValueError)            console.commands
 +-- DeviceError (ValueError)             devices
 +-- ExperimentFileError                  experiments.plan
 +-- ExperimentStopped                    experiments.runner
 +-- OutputError (OSError)                fileio
 +-- NativeLibraryError (OSError)         firmware.native
 +-- FleetError (ValueError)              fleet.model
 +-- FleetFileError                       fleet.store
 +-- LogError                             logs.jsonl
 |    +-- LogFormatError (ValueError)     logs.jsonl
 +-- TooBigError                          machine
 +-- OptionError (ValueError)             options
 +-- PlotInputError (ValueError)          plots
 +-- FrameError (ValueError)              protocol.frames
 +-- PayloadError (ValueError)            protocol.generated
 +-- AvrdudeError                         provision.avrdude
 +-- BoardError                           provision.boards
 +-- IdentityError (ValueError)           provision.identity
 +-- ImageError (ValueError)              provision.image
 +-- RadioError                           radio.base
 |    +-- InvalidRadioUrlError            radio.base
 |    +-- NoResponseError                 radio.base
 |    +-- PortBusyError                   radio.base
 |    +-- PortLostError                   radio.base
 |    +-- PortNotFoundError               radio.base
 |    +-- PortPermissionError             radio.base
 |    +-- ReadOnlyRadioError              radio.base
 |    +-- WrongModeError                  radio.base
 |    +-- RadioSetupError                 provision.xbee_setup
 +-- BootError (RuntimeError)             sim.particles.emulated.boot
 |    +-- EmulatorMissingError            sim.particles.emulated.boot
 +-- HarnessError (RuntimeError)          sim.particles.emulated.harness
 +-- HarnessBuildError (RuntimeError)     sim.particles.emulated.harness
 +-- RunError (ValueError)                sim.runs.run
 |    +-- BlownUpError                    sim.runs.run
 +-- CsvDamagedError (ValueError)         sim.runs.csvlog
 +-- SimFormatError (ValueError)          sim.runs.simcsv
 +-- VideoError (RuntimeError)            sim.runs.video
 +-- PlacementError (ValueError)          sim.scenarios.placement
 +-- ScenarioError (ValueError)           sim.scenarios.scenario
 +-- WorldRecordError (ValueError)        sim.swarm.records
 +-- SnapshotError (ValueError)           sim.world.snapshot
 +-- StudyOptionError (ValueError)        studies.definitions
 +-- ClusterError (RuntimeError)          studies.engine
 +-- PoolingError (ValueError)            studies.pooling
 +-- MeasureError (ValueError)            studies.measures
 +-- SetupError (ValueError)              studies.seam
 +-- IdInUseError (ValueError)            swarm.model
 +-- VideoError (ValueError)              videowriter
 +-- SwarmError                           swarm.results
      +-- IdInUse                         swarm.results
      +-- NotConfirmed                    swarm.results
      +-- ParticlesMissing                swarm.results

tests/test_architecture.py checks that every exception class the package defines is here.
"""


class ParticlebotError(Exception):
    """Base class of every error the particlebot package raises on purpose."""
