# The allowed dependency arrows between the project's folders
# (docs/architecture.md), checked on every build: an #include that breaks
# one fails the build with the file, the line and the rule.
#
#   cmake -DROOT=<source tree> [-DSTAMP=<file>] -P cmake/CheckIncludes.cmake
#
# Programs are on top: robot_client/, pc_server/, sim/ (mcu_sim), experiments/.
# Below them shared/robot (the decision core), below it the other shared/
# libraries; proto/ (inspect/...) at the bottom.
#   shared/*      includes inspect/ and shared/ only, and not shared/robot/
#                 (except shared/robot itself): no library includes a program
#   sim/          no robot_client/, pc_server/, experiments/, tests/, and not
#                 shared/robot/: the world does not know the robot's mind
#   robot_client/ no sim/, pc_server/, experiments/, tests/ (the world file
#                 of --map is shared/world)
#   pc_server/    no robot_client/, experiments/, tests/; inside it, floors
#                 from the bottom (each includes only floors below it):
#                 1. the parts (link/, video/, scene/, recording/, tuning/):
#                    no console/, operator/, terminal/, foxglove/, app/ (their
#                    config structs live beside them; text helpers are shared/util)
#                 2. operator/, the operator service (OperatorService,
#                    ControlArbiter, routes, command limits, StopFlag): no
#                    front end (console/, terminal/, foxglove/) and no app/
#                 3. the front ends: console/ (the commands' parser and
#                    formatter) includes no terminal/, foxglove/, app/;
#                    terminal/ (line editor, keyboard teleop, interactive
#                    console, attach socket) and foxglove/ (the bridge) stand
#                    on console/ and operator/, never on each other nor app/
#                 4. app/ (main, options, config, the consoles' wiring):
#                    included by nobody
#   firmware/core/  the MCU's logic: firmware/core/ and the serial codec
#                 (shared/serial/) only: it is built for the STM32 too
#   firmware/host/, firmware/tools/: no program (robot_client, pc_server, sim,
#                 experiments, tests)
#   experiments/  no robot_client/; of tests/ only tests/support/paths.hpp,
#                 udp_relay.hpp (the seeded lossy link of bench_video --loss) and
#                 postgres_server.hpp (bench_catalog's own PostgreSQL server)
if(NOT ROOT)
  message(FATAL_ERROR "CheckIncludes.cmake: -DROOT=<source tree> is required")
endif()

set(problems "")
set(checked 0)

# _check_includes(<folder> <regex on the include path> <DENY|ONLY> <why>): DENY
# refuses the includes that match, ONLY those that do not.
function(_check_includes folder regex mode why)
  file(GLOB_RECURSE files RELATIVE ${ROOT} ${ROOT}/${folder}/*.cpp ${ROOT}/${folder}/*.hpp)
  foreach(f IN LISTS files)
    if(DEFINED skip_regex AND f MATCHES "${skip_regex}")
      continue()
    endif()
    file(STRINGS ${ROOT}/${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
    foreach(l IN LISTS lines)
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*$" "\\1" inc "${l}")
      set(matched FALSE)
      if(inc MATCHES "${regex}")
        set(matched TRUE)
      endif()
      if((mode STREQUAL "DENY" AND matched) OR (mode STREQUAL "ONLY" AND NOT matched))
        set(problems "${problems}\n  ${f}: #include \"${inc}\": ${why}")
      endif()
    endforeach()
  endforeach()
  set(problems "${problems}" PARENT_SCOPE)
endfunction()
# check_folder(<folder> <what may not be included: a regex on the include path> <why>)
function(check_folder folder deny why)
  _check_includes(${folder} "${deny}" DENY "${why}")
  set(problems "${problems}" PARENT_SCOPE)
endfunction()
# check_folder_only(<folder> <what alone may be included: a regex> <why>)
function(check_folder_only folder allow why)
  _check_includes(${folder} "${allow}" ONLY "${why}")
  set(problems "${problems}" PARENT_SCOPE)
endfunction()

set(programs "^(robot_client|pc_server|sim|experiments|tests)/")
set(skip_regex "^shared/robot/")
check_folder(shared "${programs}|^shared/robot/" "a shared library includes neither a program nor the decision core above it")
unset(skip_regex)
check_folder(shared/robot "${programs}" "the decision core includes no program")
check_folder(sim "^(robot_client|pc_server|experiments|tests)/|^shared/robot/" "the simulator includes no other program and not the robot's decision core")
check_folder(robot_client "^(sim|pc_server|experiments|tests)/" "robot_client includes no other program (nor the simulator)")
check_folder(pc_server "^(robot_client|experiments|tests)/" "pc_server includes no other program")
foreach(part link video scene recording tuning)
  check_folder(pc_server/${part} "^pc_server/(console|operator|terminal|foxglove|sparkplug|app)/" "pc_server/${part} is below the operator service and the front ends: it includes no console/, operator/, terminal/, foxglove/, sparkplug/ or app/")
endforeach()
check_folder(pc_server/operator "^pc_server/(console|terminal|foxglove|sparkplug|app)/" "the operator service is below the front ends: it includes no console/, terminal/, foxglove/, sparkplug/ or app/")
check_folder(pc_server/console "^pc_server/(terminal|foxglove|sparkplug|app)/" "the console's parser and formatter include no terminal/, foxglove/ or app/ (front ends stand on it)")
check_folder(pc_server/terminal "^pc_server/(foxglove|sparkplug|app)/" "the terminal front end includes no foxglove/, sparkplug/ nor app/")
check_folder(pc_server/foxglove "^pc_server/(terminal|sparkplug|app)/" "the Foxglove bridge includes no terminal/, sparkplug/ nor app/")
check_folder(pc_server/sparkplug "^pc_server/(console|terminal|foxglove|app)/" "the Sparkplug edge node (SCADA's way in) stands on the operator service and the parts: no console/, terminal/, foxglove/ nor app/")
check_folder_only(firmware/core "^(firmware/core|shared/serial)/" "the firmware's core includes only firmware/core/ and shared/serial/ (it is built for the STM32)")
check_folder_only(firmware/boards "^(firmware/(boards|core|mcu)|shared/(serial|hil))/" "a board includes the core, the boards' own parts and the serial and HIL links only (it is built for the STM32)")
check_folder_only(firmware/mcu "^(firmware/(core|mcu)/|mcu_settings_gen[.]hpp$)" "the MCU build's instance includes the core and its generated settings only")
check_folder_only(shared/serial "^shared/serial/" "the serial codec includes only itself (it is built for the STM32)")
check_folder_only(shared/hil "^(shared/(hil|serial)/|shared/control/first_order[.]hpp$)" "the HIL link includes only itself, the serial codec and the first-order step (it is built for the STM32)")
check_folder(firmware/host "${programs}" "the firmware's host tools include no program")
check_folder(firmware/tools "${programs}" "the firmware's host tools include no program")
check_folder(experiments "^robot_client/|^tests/(.*/)?[a-z_]+\\.hpp$" "an experiment includes no program's code (of tests/ only tests/support/paths.hpp, udp_relay.hpp, postgres_server.hpp)")

# The allowed exception of the rule above.
string(REGEX REPLACE "\n  experiments/[^:]+: #include \"tests/support/(paths|udp_relay|postgres_server)\\.hpp\": [^\n]*" "" problems "${problems}")

if(problems)
  message(FATAL_ERROR "includes that break the dependency arrows of docs/architecture.md:${problems}")
endif()
if(STAMP)
  file(TOUCH ${STAMP})
endif()
