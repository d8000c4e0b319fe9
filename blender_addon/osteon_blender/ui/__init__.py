from . import live_properties, panel, properties

classes = properties.classes + live_properties.classes + panel.classes
