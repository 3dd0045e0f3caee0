"""locoplan.sim"""
