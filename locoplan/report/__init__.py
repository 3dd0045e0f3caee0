"""locoplan.report"""
