# The layering of docs/DESIGN.md §3, checked at configure time: a link that breaks it
# fails the configure step with the chain that reaches the forbidden target
# (mjc_forbid_dependency, cmake/MjcBuild.cmake). Included at the end of the top-level
# CMakeLists.txt, once every target exists.

# The pure algorithms: no hardware, no wire format, no application, nothing of the host.
mjc_forbid_dependency(mjc_core
  "^mjc_(hal|protocol|app|host|plant|sim|scenarios|bootloader|boot_|image|g474)")

# The wire format is shared by board and host: it knows neither the application that
# serves it nor the hardware under it.
mjc_forbid_dependency(mjc_protocol "^mjc_(hal|app|host|plant|sim|scenarios|g474)")

# The application runs on the board: never the plant, the simulator or the host tools,
# and only the HAL's interfaces, never a backend.
mjc_forbid_dependency(mjc_app
  "^mjc_(plant|sim_|scenarios|host|strict_json|hal_stm32g4|g474)")

if(TARGET mjc_gpio)
  # The host's GPIO lines are lines: what they mean for the boards is the host tools'.
  mjc_forbid_dependency(mjc_gpio
    "^mjc_(core|hal|protocol|app|host|plant|sim|scenarios|bootloader|boot_|image|g474)")
endif()

if(TARGET mjc_plant)
  # The plant is physics: it must not replay the firmware (not even its core's
  # algorithms or the sensor decoding it is tested against) or talk CAN.
  mjc_forbid_dependency(mjc_plant "^mjc_(core|app|protocol|host|sim_board|scenarios|hal)")
endif()

if(TARGET mjc_g474_model)
  # The register models are written from the reference manual, never from the drivers:
  # they do not even see the drivers' register tables.
  mjc_forbid_dependency(mjc_g474_model "^mjc_(hal|app|protocol|boot)")
endif()

# The joint service is the board's main loop around the application: it knows no
# transport (not the CAN node, not the board that composes them) and, like the
# application, nothing of the host.
mjc_forbid_dependency(mjc_service
  "^mjc_(app$|app_can_node|plant|sim_|scenarios|host|strict_json|hal_stm32g4|g474)")

# The application's core knows neither the main loop around it nor a transport.
mjc_forbid_dependency(mjc_app_core "^mjc_(service|app_can_node|app$)")

# The CAN node is a transport: it reaches the application only through the service
# (never links mjc_app_core itself), and never the board that composes it.
mjc_forbid_dependency(mjc_app_can_node "^mjc_app$")
foreach(kind LINK_LIBRARIES INTERFACE_LINK_LIBRARIES)
  get_target_property(direct mjc_app_can_node ${kind})
  foreach(dep IN LISTS direct)
    string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" dep "${dep}")
    if(dep STREQUAL "mjc_app_core")
      message(FATAL_ERROR
        "layering: mjc_app_can_node must reach mjc_app_core only through mjc_service")
    endif()
  endforeach()
endforeach()
