"""locoplan.robot"""
