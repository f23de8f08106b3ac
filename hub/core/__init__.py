"""The kernel: slots, the one state object, components, modules, flows, the registry, errors and the logic-slave contract; imports nothing else of hub."""
