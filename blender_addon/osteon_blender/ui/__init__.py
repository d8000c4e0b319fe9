from . import panel, properties

classes = properties.classes + panel.classes
