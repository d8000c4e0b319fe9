from . import live_properties, panel, print_settings, properties

# the print-settings group before scene.osteon (its pointer), its panel after its parent's
classes = (print_settings.property_classes + properties.classes + live_properties.classes
           + panel.classes + print_settings.panel_classes)
